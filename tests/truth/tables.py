"""The two tables (EERC, LNEC) and the effects switched on them.

Effect names and parameter units follow vtable's catalog (docs/effects.md); the
three effects below the line are outside that catalog. Parameters are given in these
units and converted to SI when the model is built (`model.build`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from . import constants as c
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
    # ---- outside vtable's catalog ----
    # a dead band between piston and platen: force passes only beyond ±gap/2
    "backlash": {"gap_in": ("in", 0.01, 0.0, 1.0)},
    # first storey elastic-plastic (Bouc-Wen, n = 8, bilinear-like), yielding at a base
    # shear yield_fraction x the specimen weight; post-yield stiffness ratio alpha
    "yielding_storey": {"yield_fraction": ("1", 0.2, 1e-3, 5.0),
                        "post_yield_ratio": ("1", 0.02, 0.0, 0.5)},
    # supply pressure sags with the flow drawn: P_s = P_s0 - drop * |Q| (needs
    # valve_flow_nonlinearity, whose orifice flow depends on P_s)
    "pump_pressure_drop": {"drop_psi_per_gpm": ("psi/gpm", 1.0, 0.0, 50.0)},
}
OUTSIDE_CATALOG = ("backlash", "yielding_storey", "pump_pressure_drop")
PITCH_FAMILIES = ("none", "hybrid", "two_directional")


def check_effects(effects: dict | None, where: str) -> dict[str, dict[str, float]]:
    """Fill defaults; unknown names, unknown parameters and out-of-range values are errors."""
    out: dict[str, dict[str, float]] = {}
    for name, params in (effects or {}).items():
        if name not in EFFECTS:
            raise TruthError(f"{where}: unknown effect {name!r}; known: {', '.join(EFFECTS)}")
        if not isinstance(params, dict):
            raise TruthError(f"{where}: effect {name!r} needs a dict of parameters")
        spec = EFFECTS[name]
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
    controller: str  # "three_variable" | "pid"
    k_t: float = 0.0  # m²/s, lumped flow per metre of error (three_variable)
    k_p: float = 0.0  # m/Pa, ΔP feedback (three_variable)
    valve_gain: float = 0.0  # m³/s/V (pid)
    disp_gain: float = 0.0  # V/m (pid)
    pid: tuple[float, float, float] = (1.0, 0.0, 0.0)  # P (1), I (1/s), D (s)
    feedforward: float = 0.0  # fraction of the ideal velocity feedforward A·v_c/K_q (pid)
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


def eerc_table(pitch: str = "none", com_height_in: float = 0.0, effects: dict | None = None,
               open_loop: tuple[float, float, float] | None = None) -> Table:
    """The EERC table: 3 horizontal actuators lumped into one (Table B.5 x 3), platen
    100 kips/g and 1251 kip-in-s² (Table 8.1), c.o.m. `com_height_in` above the actuator
    line.

    pitch: "none" (θ ≡ 0, eq 7.7 family), "hybrid" (eq 8.37: k_θ, c_θ of Table 8.1 or of
    effect pitch_flexibility), "two_directional" (eq 8.16: pitch servo loop at 21 Hz plus
    passive stabilizers, together matching k_θ, c_θ at 2.58 Hz).
    open_loop: (f_o Hz, ξ_o, k_o 1/s) instead of the physical constants (eq 6.15/7.6 form,
    normalised by the bare platen mass, as Tables 7.1, 8.1 and 9.1 are).
    """
    eff = check_effects(effects, "eerc_table")
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
    return Table("eerc", pitch, m_t, c.EERC_PITCH_INERTIA, com_height_in * c.INCH, n, area,
                 volume, beta, k_ct, "three_variable", k_t=k_t, k_p=k_p, supply_pressure=ps,
                 k_theta=k_th, c_theta=c_th, open_loop=open_loop, effects=eff)


def lnec_table(effects: dict | None = None, pid: tuple[float, float, float] = (1.0, 0.0, 0.0),
               feedforward: float = 0.0) -> Table:
    """The LNEC uniaxial table ("lnec-st1d"): one actuator, PID on the displacement error in
    volts (P 1, I 0, D 0 by default), optional velocity feedforward (a fraction of A·v_c/K_q),
    intrinsic servovalve lag 0.0246 s (the effect valve_dynamics replaces it), no pitch."""
    eff = check_effects(effects, "lnec_table")
    for bad in ("pitch_flexibility", "force_feedback_filter"):
        if bad in eff:
            raise TruthError(f"lnec_table: effect {bad!r} does not apply (no pitch, no ΔP "
                             "feedback on this table)")
    L = c.LNEC
    ps = eff.get("valve_flow_nonlinearity", {}).get("supply_pressure", 3000.0) * c.PSI
    return Table("lnec-st1d", "none", L["platen_mass"], 0.0, 0.0, 1, L["area"], L["volume"],
                 L["beta"], L["leakage"], "pid", valve_gain=L["valve_gain"],
                 disp_gain=L["disp_gain"], pid=tuple(float(x) for x in pid),
                 feedforward=float(feedforward), valve_tau=L["valve_tau"],
                 platen_damping=L["damping"], supply_pressure=ps,
                 foundation_mass=50 * L["platen_mass"], effects=eff)
