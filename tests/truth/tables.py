"""The two tables (EERC, LNEC) and the effects switched on them.

Effect names and parameter units follow vtable's catalog (docs/effects.md); the
three effects below the line are outside that catalog. Parameters are given in these
units and converted to SI when the model is built (`model.build`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from . import constants as c
from . import controllers as ctl
from .controllers import Controller
from .errors import TruthError

#: name -> {parameter: (unit, default, lower, upper)}
EFFECTS: dict[str, dict[str, tuple[str, float | None, float, float]]] = {
    "pitch_flexibility": {"k_theta": ("lb-in/rad", 2.22e10, 1e8, 1e13),
                          "c_theta": ("lb-in-s/rad", 3.70e8, 1e5, 1e11)},
    "force_feedback_filter": {"rc": ("s", 0.01, 1e-4, 10.0)},
    "valve_flow_nonlinearity": {"supply_pressure": ("psi", 3000.0, 100.0, 10000.0)},
    "actuator_friction": {"friction": ("kip", 1.0, 0.0, 100.0)},
    "flow_saturation": {"v_max": ("in/s", 25.0, 0.1, 200.0)},
    "valve_dynamics": {"tau": ("s", 0.002, 1e-5, 0.2), "delay": ("s", 0.0, 0.0, 0.1)},
    "oil_column_air": {"air_ratio": ("1", 0.01, 0.0, 0.5)},
    "amplitude_dependent_damping": {"gamma": ("1/in", 0.01, 0.0, 5.0)},
    "foundation_compliance": {"f_f": ("Hz", 10.0, 0.5, 200.0), "xi_f": ("1", 0.1, 0.0, 2.0)},
    "sensor_filter": {"cutoff_hz": ("Hz", 100.0, 1.0, 1000.0)},
    # the table accelerometer on a mount (resonance, damping) behind its conditioner's
    # second-order Butterworth low-pass; only avg_hacc sees it
    "sensor_mount": {"f_m": ("Hz", 60.0, 1.0, 1000.0), "zeta_m": ("1", 0.05, 1e-3, 2.0),
                     "f_c": ("Hz", 100.0, 1.0, 1000.0)},
    # first storey elastic-plastic (Bouc-Wen, n = 8, bilinear-like), yielding at a base
    # shear yield_fraction x the specimen weight; post-yield stiffness ratio alpha (vtable's
    # storey_yield, whose sharpness n it fits: `CATALOG_NAME`)
    "yielding_storey": {"yield_fraction": ("1", 0.2, 1e-3, 5.0),
                        "post_yield_ratio": ("1", 0.02, 0.0, 0.5)},
    # ---- outside vtable's catalog ----
    # a dead band between piston and platen: force passes only beyond ±gap/2
    "backlash": {"gap_in": ("in", 0.01, 0.0, 1.0)},
    # supply pressure sags with the flow drawn: P_s = P_s0 - drop * |Q| (needs
    # valve_flow_nonlinearity, whose orifice flow depends on P_s)
    "pump_pressure_drop": {"drop_psi_per_gpm": ("psi/gpm", 1.0, 0.0, 50.0)},
}
OUTSIDE_CATALOG = ("backlash", "pump_pressure_drop")
#: the truth's effects that vtable's catalog holds under another name
CATALOG_NAME = {"yielding_storey": "storey_yield"}
#: catalog effects issue 18 adds (kept out of EFFECTS, whose catalog part issue 12's
#: scorecard covers case by case); accepted wherever EFFECTS are
NEW_EFFECTS: dict[str, dict[str, tuple[str, float | None, float, float]]] = {
    # an undeclared mass-spring-damper on the platen: m_r ẍ_r = -k_r(x_r - x_t) - c_r(ẋ_r -
    # ẋ_t), k_r = m_r ω_r², c_r = 2 ξ_r m_r ω_r (an undocumented specimen, a table mode)
    "platen_resonator": {"f_r": ("Hz", 8.0, 0.5, 200.0), "xi_r": ("1", 0.02, 1e-4, 1.0),
                         "m_r": ("kg", 1000.0, 1.0, 1e6)},
    # (issue 32's, covered by tests/scorecard.py CASES_32) the specimen's stiffness matrix
    # scaled by 1 - stiffness_loss (1 - exp(-E/E0)), E the energy its viscous damping has
    # dissipated since the run began (E0 = energy_kip_in)
    "specimen_degradation": {"stiffness_loss": ("1", 0.15, 0.0, 0.9),
                             "energy_kip_in": ("kip-in", 10.0, 1e-6, 1e9)},
    # the table accelerometer reads a + zero + drift·t: its conditioner's zero (m/s²) and a
    # slow drift of it since zeroing (m/s² per s); only avg_hacc sees it
    "sensor_offset": {"zero_m_s2": ("m/s2", 0.1, -10.0, 10.0),
                      "drift_m_s3": ("m/s3", 0.0, -1.0, 1.0)},
}
FORCE_MEASURED = ("load_cell", "delta_p")
PITCH_FAMILIES = ("none", "hybrid", "two_directional")


def check_effects(effects: dict | None, where: str) -> dict[str, dict[str, float]]:
    """Fill defaults; unknown names, unknown parameters and out-of-range values are errors."""
    out: dict[str, dict[str, float]] = {}
    known = {**EFFECTS, **NEW_EFFECTS}
    for name, params in (effects or {}).items():
        if name not in known:
            raise TruthError(f"{where}: unknown effect {name!r}; known: {', '.join(known)}")
        if not isinstance(params, dict):
            raise TruthError(f"{where}: effect {name!r} needs a dict of parameters")
        spec = known[name]
        for k in params:
            if k not in spec:
                raise TruthError(f"{where}: effect {name!r} has no parameter {k!r}; expected "
                                 f"{', '.join(spec)}")
        vals = {}
        for k, (unit, default, lo, hi) in spec.items():
            v = float(params.get(k, default))
            if not (math.isfinite(v) and lo <= v <= hi):
                raise TruthError(f"{where}: {name}.{k} = {v:g} {unit} is outside [{lo:g}, {hi:g}]")
            vals[k] = v
        out[name] = vals
    if "pump_pressure_drop" in out and "valve_flow_nonlinearity" not in out:
        raise TruthError(f"{where}: pump_pressure_drop needs valve_flow_nonlinearity (the "
                         "orifice flow is what depends on the supply pressure)")
    return out


@dataclass(frozen=True)
class Table:
    """A shaking table: platen, one lumped horizontal actuator and its controller, the
    pitch family and the effects. All SI (see `eerc_table`, `lnec_table`)."""

    preset: str  # "eerc" | "lnec-st1d"
    pitch: str  # none | hybrid | two_directional
    platen_mass: float  # kg
    pitch_inertia: float  # kg·m² about the actuator line
    com_height: float  # m, platen c.o.m. above the actuator line
    actuators: int
    area: float  # m², lumped (all actuators)
    volume: float  # m³, lumped oil volume (both chambers)
    beta: float  # Pa
    leakage: float  # m³/s/Pa (k_ct or the LNEC leakage)
    controller: str  # "three_variable" | "pid" | "tvc"
    k_t: float = 0.0  # m²/s, lumped flow per metre of error (analog three_variable)
    k_p: float = 0.0  # m/Pa, ΔP feedback (analog three_variable)
    valve_gain: float = 0.0  # m³/s/V, lumped K_q (a law in volts)
    law: Controller | None = None  # None: the analog loop of Table B.5 (k_t, k_p)
    declare_controller: bool = False  # write [table.controller] (not the preset's own)
    force_measured: str | None = None  # None: A·ΔP, undeclared (the runs before issue 18)
    valve_tau: float = 0.0  # s, intrinsic servovalve lag (LNEC); 0 = none
    platen_damping: float = 0.0  # N·s/m
    supply_pressure: float = c.EERC_SUPPLY_PRESSURE  # Pa, sets chamber pressures P_s/2
    foundation_mass: float = c.EERC_FOUNDATION_WEIGHT / c.G
    k_theta: float = c.T81_K_THETA  # N·m/rad, hybrid / two_directional total at 2.58 Hz
    c_theta: float = c.T81_C_THETA
    open_loop: tuple[float, float, float] | None = None  # (f_o, ξ_o, k_o) if so described
    effects: dict[str, dict[str, float]] = field(default_factory=dict)

    @property
    def physical(self) -> bool:
        return self.open_loop is None


def _check_common(where: str, force_measured: str | None, platen_mass_factor: float) -> None:
    if force_measured is not None and force_measured not in FORCE_MEASURED:
        raise TruthError(f"{where}: force_measured must be one of {', '.join(FORCE_MEASURED)} "
                         f"or None, got {force_measured!r}")
    if not (math.isfinite(platen_mass_factor) and 0.2 <= platen_mass_factor <= 5.0):
        raise TruthError(f"{where}: platen_mass_factor must be in [0.2, 5], got "
                         f"{platen_mass_factor!r}")


def eerc_table(pitch: str = "none", com_height_in: float = 0.0, effects: dict | None = None,
               open_loop: tuple[float, float, float] | None = None,
               controller: Controller | None = None, force_measured: str | None = None,
               platen_mass_factor: float = 1.0) -> Table:
    """The EERC table: 3 horizontal actuators lumped into one (Table B.5 x 3), platen
    100 kips/g and 1251 kip-in-s² (Table 8.1), c.o.m. `com_height_in` above the actuator
    line.

    pitch: "none" (θ ≡ 0, eq 7.7 family), "hybrid" (eq 8.37: k_θ, c_θ of Table 8.1 or of
    effect pitch_flexibility), "two_directional" (eq 8.16: pitch servo loop at 21 Hz plus
    passive stabilizers, together matching k_θ, c_θ at 2.58 Hz).
    open_loop: (f_o Hz, ξ_o, k_o 1/s) instead of the physical constants (eq 6.15/7.6 form,
    normalised by the bare platen mass, as Tables 7.1, 8.1 and 9.1 are).
    controller: a digital controller (controllers.py) instead of the analog loop; the
    valve flow gain is K_q = k_t / k_d at the assumed transducer gain k_d =
    `EERC_DISPLACEMENT_GAIN`, so that p = 1, k_dp = k_p k_d is the Table B.5 loop.
    force_measured: what the force channels measure and the run declares ("load_cell",
    "delta_p"); None: A·ΔP, not declared.
    platen_mass_factor: the true platen mass over the preset's (the run still declares
    the preset: a mis-declared platen).
    """
    eff = check_effects(effects, "eerc_table")
    _check_common("eerc_table", force_measured, platen_mass_factor)
    if pitch not in PITCH_FAMILIES:
        raise TruthError(f"eerc_table: pitch must be one of {', '.join(PITCH_FAMILIES)}, "
                         f"got {pitch!r}")
    if "pitch_flexibility" in eff and pitch == "none":
        pitch = "hybrid"
    k_th = eff.get("pitch_flexibility", {}).get("k_theta", 2.22e10) * c.LB_IN
    c_th = eff.get("pitch_flexibility", {}).get("c_theta", 3.70e8) * c.LB_IN
    n = c.EERC_ACTUATORS
    m_t = c.EERC_PLATEN_WEIGHT / c.G
    area, volume = n * c.B5_AREA, n * c.B5_VOLUME
    if open_loop is None:
        beta, k_t, k_p, k_ct = c.B5_BETA, n * c.B5_KT, c.B5_KP, n * c.B5_KCT
    else:
        f_o, xi_o, k_o = (float(x) for x in open_loop)
        if not (f_o > 0 and xi_o > 0 and k_o > 0):
            raise TruthError(f"eerc_table: open_loop (f_o, ξ_o, k_o) must be positive, got "
                             f"{open_loop}")
        if "force_feedback_filter" in eff:
            raise TruthError("eerc_table: force_feedback_filter needs the physical constants "
                             "(an open-loop description has no separate ΔP feedback)")
        w_o = 2 * math.pi * f_o
        # eq 7.6 matched term by term with (V/4β)Ṗ = k_t(x_c - x_t) - k_ct P - A ẋ_t, F = A P:
        # V/(4βA²) = 1/(m_t ω_o²), k_ct/A² = 2ξ_o/(m_t ω_o), k_t/A = k_o
        beta = m_t * w_o**2 * volume / (4 * area**2)
        k_t, k_p, k_ct = k_o * area, 0.0, 2 * xi_o * area**2 / (m_t * w_o)
    ps = eff.get("valve_flow_nonlinearity", {}).get("supply_pressure", 3000.0) * c.PSI
    kind = "three_variable" if controller is None else controller.kind
    return Table("eerc", pitch, m_t * platen_mass_factor, c.EERC_PITCH_INERTIA,
                 com_height_in * c.INCH, n, area, volume, beta, k_ct, kind, k_t=k_t, k_p=k_p,
                 valve_gain=k_t / c.EERC_DISPLACEMENT_GAIN, law=controller,
                 declare_controller=controller is not None, force_measured=force_measured,
                 supply_pressure=ps, k_theta=k_th, c_theta=c_th, open_loop=open_loop,
                 effects=eff)


def lnec_table(effects: dict | None = None, pid: tuple[float, float, float] = (1.0, 0.0, 0.0),
               feedforward: float = 0.0, controller: Controller | None = None,
               force_measured: str | None = None, platen_mass_factor: float = 1.0) -> Table:
    """The LNEC uniaxial table ("lnec-st1d"): one actuator, PID on the displacement error in
    volts (P 1, I 0, D 0 by default), optional velocity feedforward (a fraction of A·v_c/K_q,
    i.e. T_v = fraction·A/(K_q k_d)), intrinsic servovalve lag 0.0246 s (the effect
    valve_dynamics replaces it), no pitch. These two are the preset's own loop, not
    declared; `controller` (controllers.py) replaces them and is declared in the run.
    force_measured, platen_mass_factor: as for `eerc_table`."""
    eff = check_effects(effects, "lnec_table")
    _check_common("lnec_table", force_measured, platen_mass_factor)
    if controller is not None and (tuple(pid) != (1.0, 0.0, 0.0) or feedforward):
        raise TruthError("lnec_table: give pid/feedforward or controller, not both")
    L = c.LNEC
    if controller is None:
        law = ctl.pid(L["disp_gain"], *(float(x) for x in pid),
                      feedforward_velocity=float(feedforward) * L["area"]
                      / (L["valve_gain"] * L["disp_gain"]))
    else:
        law = controller
    if "pitch_flexibility" in eff:
        raise TruthError("lnec_table: effect 'pitch_flexibility' does not apply (no pitch on "
                         "this table)")
    if "force_feedback_filter" in eff and law.pressure_gain == 0:
        raise TruthError("lnec_table: effect 'force_feedback_filter' does not apply (no ΔP "
                         "feedback on this table's controller)")
    ps = eff.get("valve_flow_nonlinearity", {}).get("supply_pressure", 3000.0) * c.PSI
    return Table("lnec-st1d", "none", L["platen_mass"] * platen_mass_factor, 0.0, 0.0, 1,
                 L["area"], L["volume"], L["beta"], L["leakage"], law.kind,
                 valve_gain=L["valve_gain"], law=law,
                 declare_controller=controller is not None, force_measured=force_measured,
                 valve_tau=L["valve_tau"], platen_damping=L["damping"], supply_pressure=ps,
                 foundation_mass=50 * L["platen_mass"], effects=eff)
