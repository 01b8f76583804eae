"""Parameters of the multibody virtual table, shared by the MJCF builder, the controllers
and the consistent analytic model (one object, nothing typed twice).

Where the report is silent (rib size, actuator lengths) `eerc.toml [multibody]` says so.
Two sets are *derived* from the report rather than typed:

- passive stabilizers: per-piston stiffness F/Δx = 2β_e A²/V (eq 8.3, oil term) with the
  volume V chosen so that eq 8.4 gives k_p = k_θ (Table 8.1) - k_v(ω_c) (§8.6.2), and
  per-piston damping from c_p = c_θ - c_v(ω_c);
- vertical actuators: the servo constants (k_t, V, k_p) that make the pitch DOF loop the
  §8.6.2 loop (f_r = 21 Hz, ξ_r, k_r from eqs 8.28-8.29 inverted), by eq 6.16 with the
  equivalent mass I/ΣT_i² per actuator (T_i = lever arm of V_i, 72 in).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from vtable import units
from vtable.analytic.closed_forms import stabilizer_rocking
from vtable.analytic.servo import servo_from_open_loop
from vtable.errors import VtableError
from vtable.params import presets
from vtable.params.base import Params, plain, quantity
from vtable.params.loops import OpenLoop
from vtable.params.table import (
    ActuatorSpec,
    ControlSettings,
    DirectionSettings,
    EERCTable,
    KnobFactors,
    ServoConstants,
    TableGeometry,
    TableSpecs,
)


@dataclass(frozen=True)
class MultibodyLayout(Params):
    """Layout assumptions of the multibody table (eerc.toml [multibody])."""

    rib_width: float = quantity("in", "rib_width_in", minimum=0, exclusive=False)
    rib_depth: float = quantity("in", "rib_depth_in", minimum=0, exclusive=False)
    rib_offset: float = quantity("in", "rib_offset_in", minimum=0, exclusive=False)
    horizontal_length: float = quantity("in", "horizontal_length_in", minimum=0)
    vertical_length: float = quantity("in", "vertical_length_in", minimum=0, exclusive=False)
    stabilizer_length: float = quantity("in", "stabilizer_length_in", minimum=0, exclusive=False)
    stabilizer_beta: float = quantity("psi", "stabilizer_beta_psi", minimum=0)
    vertical_k_ct: float = quantity("in3/s/psi", "vertical_k_ct_in3_per_s_per_psi", minimum=0,
                                    exclusive=False)
    pitch_loop_f: float = quantity("Hz", "pitch_loop_f_hz", minimum=0, exclusive=False)
    twist_gain_factor: float = plain()
    twist_delta_p_factor: float = plain()
    roll_delta_p_factor: float = plain()
    source: str = plain(default="")


@dataclass(frozen=True)
class Actuator:
    """One actuator or stabilizer: attachment on the slab and on the foundation (SI,
    world frame at rest, origin at the table-top centre), and its DOF participation."""

    name: str
    kind: str  # "horizontal" | "vertical" | "stabilizer"
    slab_point: tuple[float, float, float]
    foundation_point: tuple[float, float, float]
    area: float
    stroke: float
    capacity: float
    flow: float | None

    @property
    def axis(self) -> np.ndarray:
        d = np.subtract(self.slab_point, self.foundation_point)
        return d / np.linalg.norm(d)


@dataclass(frozen=True)
class Stabilizers:
    """Cross-connected passive stabilizers (§8.3): per-piston stiffness and damping acting
    on the antisymmetric motion of each pair only."""

    pairs: tuple[tuple[str, str], ...]
    stiffness: float  # F/Δx per piston, N/m (eq 8.3, oil term)
    damping: float  # N s/m per piston
    volume: float  # oil volume per side, m³
    beta: float


@dataclass(frozen=True)
class VirtualTable:
    """Everything the multibody table, its controllers and the consistent analytic model
    need, built once from the EERC preset (`virtual_table()`)."""

    table: EERCTable
    layout: MultibodyLayout
    actuators: tuple[Actuator, ...]
    horizontal_servo: ServoConstants  # Table B.5, per horizontal actuator
    vertical_servo: ServoConstants | None  # derived (module docstring), per vertical actuator
    pitch_loop: OpenLoop | None  # §8.6.2 target of the vertical calibration
    stabilizers: Stabilizers
    settings: dict[str, DirectionSettings]
    dofs: tuple[str, ...] = ("x", "z", "roll", "pitch", "twist")  # the platen's DOFs
    knobs: bool = True  # the Table 3.2 knobs scale the gains (False: physical gains, a PID)
    valve_lag: float = 0.0  # s: the horizontal servovalves' time constant
    #: the horizontal controller's control stage and its parameters (a digital
    #: controller's terms beyond eqs 6.1-6.4: `vtable.controllers.kinds`); None: none
    control: tuple | None = None
    name: str = "eerc"
    com_height: float | None = None  # m: platen c.o.m. above the actuator line (None: shape's)
    #: what the horizontal force channels measure: "load_cell", the net force the rod
    #: transmits to the platen (after friction and any force stage); "delta_p", A·ΔP
    force_measured: str = "load_cell"
    #: the run-format [table] the table was declared with (`LabTable.declared`)
    declared: dict | None = field(default=None, compare=False)

    @property
    def limits_source(self) -> str:
        """Where the table's limits come from (for messages)."""
        return "Table 2.2" if self.name == "eerc" else f"the {self.name} table's limits"

    @property
    def pivot_depth(self) -> float:
        """Depth of the horizontal actuator line below the table top (m), §4.2.1."""
        return self.table.geometry.actuator_line_depth

    def actuator(self, name: str) -> Actuator:
        for a in self.actuators:
            if a.name == name:
                return a
        raise VtableError(f"no actuator {name!r}")

    def group(self, kind: str) -> tuple[Actuator, ...]:
        return tuple(a for a in self.actuators if a.kind == kind)

    def with_settings(self, **dirs: DirectionSettings) -> VirtualTable:
        unknown = set(dirs) - set(self.settings)
        if unknown:
            raise VtableError(f"unknown control direction {sorted(unknown)[0]!r}")
        return replace(self, settings={**self.settings, **dirs})

    def gain_scales(self, direction: str) -> tuple[float, float, float]:
        """(gain, ΔP, rate) multipliers of a DOF relative to the calibrated reference, from
        the knob factors (Tables B.1-B.4 plus the [multibody] assumptions); 1 for a table
        whose gains are physical (a PID)."""
        if not self.knobs:
            return 1.0, 1.0, 1.0
        s = self.settings[direction]
        kf = self.table.knob_factors
        lay = self.layout
        if direction == "horizontal":
            ref = self.table.standard.horizontal
            return tuple(_ratio(kf.factor("horizontal", k, getattr(s, k)),
                                kf.factor("horizontal", k, getattr(ref, k)))
                         for k in ("gain", "delta_p", "rate"))  # type: ignore[return-value]
        if direction == "twist":
            g_ref = kf.factor("horizontal", "gain", self.table.standard.horizontal.gain)
            p_ref = kf.factor("horizontal", "delta_p", self.table.standard.horizontal.delta_p)
            std = self.table.standard.twist
            g = lay.twist_gain_factor * (s.gain / std.gain if std.gain else 1.0)
            p = lay.twist_delta_p_factor * (s.delta_p / std.delta_p if std.delta_p else 1.0)
            return g / g_ref, p / p_ref, 0.0
        # vertical group: anchored at the pitch standard setting (the calibration)
        ref = self.table.standard.pitch
        g_ref = kf.factor("pitch", "gain", ref.gain)
        p_ref = kf.factor("pitch", "delta_p", ref.delta_p)
        g = kf.factor(direction, "gain", s.gain)
        if direction == "roll":
            p = lay.roll_delta_p_factor * (s.delta_p / 2.0)
        else:
            p = kf.factor(direction, "delta_p", s.delta_p)
        return g / g_ref, p / p_ref, 0.0


def _ratio(a: float, b: float) -> float:
    return a / b if b else 0.0


def _actuators(table: EERCTable, lay: MultibodyLayout) -> tuple[Actuator, ...]:
    g = table.geometry
    half = g.plan_width / 2
    line = -g.actuator_line_depth
    bottom = -g.thickness
    out = []
    hs = [a for a in table.actuators if a.name.startswith("H")]
    ys = np.linspace(g.horizontal_offset, -g.horizontal_offset, len(hs)) if len(hs) > 1 \
        else np.zeros(1)
    for spec, y in zip(hs, ys, strict=True):  # H1 at +y, ... (run format: y = +96, 0, -96 in)
        out.append(Actuator(spec.name, "horizontal", (-half, float(y), line),
                            (-half - lay.horizontal_length, float(y), line),
                            spec.area, spec.stroke, spec.capacity, spec.flow))
    if not any(a.name.startswith("V") for a in table.actuators):
        return tuple(out)
    v, p = g.vertical_square / 2, g.stabilizer_square / 2
    # run format: V1 (+,+), V2 (-,+), V3 (-,-), V4 (+,-); P likewise
    signs = ((1, 1), (-1, 1), (-1, -1), (1, -1))
    for i, (sx, sy) in enumerate(signs, 1):
        spec = table.actuator(f"V{i}")
        out.append(Actuator(f"V{i}", "vertical", (sx * v, sy * v, bottom),
                            (sx * v, sy * v, bottom - lay.vertical_length),
                            spec.area, spec.stroke, spec.capacity, spec.flow))
    for i, (sx, sy) in enumerate(signs, 1):
        spec = table.actuator(f"P{i}")
        out.append(Actuator(f"P{i}", "stabilizer", (sx * p, sy * p, bottom),
                            (sx * p, sy * p, bottom - lay.stabilizer_length),
                            spec.area, spec.stroke, spec.capacity, None))
    return tuple(out)


def vertical_servo_for_pitch_loop(ol: OpenLoop, inertia: float, lever: float, n: int,
                                  area: float, beta: float, k_ct: float) -> ServoConstants:
    """Per-actuator constants whose pitch DOF loop is `ol`: eq 6.16 solved for k_t, V and
    k_p (`servo_from_open_loop`, solve_for="feedback") with k_v = 0 and the equivalent
    mass m = I/(n·lever²): k = k_o A, V = 4βA²/(m ω_o²), k_f = (2ξ_o A/(m ω_o) - k_c)/k."""
    m = inertia / (n * lever**2)
    held = ServoConstants(k_p=0.0, k_t=1.0, k_ct=k_ct, rc=0.01, mass=m, beta=beta, area=area,
                          volume=1.0, k_v=0.0,  # k_t, V, k_p: solved below
                          source="derived: pitch DOF loop = §8.6.2 loop (params/virtual.py)")
    return servo_from_open_loop(ol, held, solve_for="feedback")


def split_rocking(k_theta: float, c_theta: float, vt: VirtualTable) -> tuple[float, float]:
    """Per-piston stabilizer stiffness and damping so that, with the pitch loop of the
    vertical actuators, the table's rocking spring and dashpot at the §8.6.3 coupled
    frequency (2.58 Hz) are k_θ and c_θ: the stabilizers' share (eqs 8.32-8.33,
    `stabilizer_rocking`) over d_p² (eq 8.4)."""
    g = vt.table.geometry
    k_p, c_p = stabilizer_rocking(k_theta, c_theta, g.pitch_inertia, vt.pitch_loop,
                                  presets.pitch_springs().f_coupled)
    d_p = g.stabilizer_square
    return k_p / d_p**2, c_p / d_p**2


def _stabilizers(vt: VirtualTable, k_theta: float, c_theta: float) -> Stabilizers:
    """The stabilizers of `vt` retuned to a rocking spring/dashpot (k_θ, c_θ); the oil
    volume per side from F/Δx = 2β A²/V (eq 8.3)."""
    k, c = split_rocking(k_theta, c_theta, vt)
    a_p = vt.table.actuator("P1").area
    s = vt.stabilizers
    return replace(s, stiffness=k, damping=c, volume=2 * s.beta * a_p**2 / k)


def with_rocking(vt: VirtualTable, k_theta: float, c_theta: float) -> VirtualTable:
    """The table with its stabilizers retuned to a rocking spring/dashpot (k_θ, c_θ)."""
    return replace(vt, stabilizers=_stabilizers(vt, k_theta, c_theta))


def virtual_table(table: EERCTable | None = None,
                  layout: MultibodyLayout | None = None) -> VirtualTable:
    """The EERC virtual table from the presets: the stabilizers carry Table 8.1's rocking
    spring less the pitch loop's (`with_rocking`)."""
    table = table or presets.eerc_table()
    if layout is None:
        layout = MultibodyLayout.from_dict(presets.data("eerc")["multibody"],
                                           "eerc.toml [multibody]")
    g = table.geometry
    pitch = presets.pitch_loop(layout.pitch_loop_f, g.pitch_inertia)
    v1 = table.actuator("V1")
    vert = vertical_servo_for_pitch_loop(pitch, g.pitch_inertia, g.vertical_square / 2, 4,
                                         v1.area, table.servo.beta, layout.vertical_k_ct)
    settings = {k: getattr(table.standard, k) for k in
                ("horizontal", "pitch", "vertical", "roll", "twist")}
    unset = Stabilizers(pairs=(("P1", "P2"), ("P4", "P3")), stiffness=0.0, damping=0.0,
                        volume=0.0, beta=layout.stabilizer_beta)
    vt = VirtualTable(table=table, layout=layout, actuators=_actuators(table, layout),
                      horizontal_servo=table.servo, vertical_servo=vert, pitch_loop=pitch,
                      stabilizers=unset, settings=settings)
    rock = presets.hybrid_rocking()
    return with_rocking(vt, rock.k_theta, rock.c_theta)


def virtual_table_for(lab) -> VirtualTable:
    """The multibody table of a `vtable.runs.lab.LabTable`: the EERC table itself, or a
    uniaxial platen (`uniaxial_table`); what the lab description changes of the EERC
    table (its mass, its loop constants) is applied to the EERC model; the controller's
    own terms (a control stage) go with it."""
    if lab.name == "eerc" and lab.uniaxial is False:
        vt = virtual_table()
        if lab.servo != replace(vt.horizontal_servo, mass=lab.servo.mass) or \
                abs(lab.platen_mass - vt.table.geometry.mass) > 1e-9 * lab.platen_mass:
            g = replace(vt.table.geometry, weight=lab.platen_mass * units.G)
            servo = replace(lab.servo, mass=vt.horizontal_servo.mass)
            vt = replace(vt, table=replace(vt.table, geometry=g), horizontal_servo=servo)
        return replace(vt, valve_lag=lab.valve_time_constant,
                       force_measured=lab.force_measured, control=lab.control,
                       declared=lab.declared)
    if not lab.uniaxial:
        raise VtableError(f"table {lab.name!r}: the virtual table models the EERC table or a "
                          f"uniaxial platen, not DOFs {', '.join(lab.dofs)}")
    return uniaxial_table(lab)


def uniaxial_table(lab) -> VirtualTable:
    """A platen on a slide in x driven by its horizontal actuators (lumped or several, side
    by side), their loop from the lab's description, physical gains (no knobs). The shape
    the description does not give — a steel plate of the platen's mass, the actuators' pin
    lengths — comes from params/data/uniaxial_multibody.toml (each number marked assumed)."""
    d = presets.data("uniaxial_multibody")
    lay = MultibodyLayout.from_dict(d["layout"], "uniaxial_multibody.toml [layout]")
    rho, aspect = d["plate"]["density_kg_m3"], d["plate"]["width_over_thickness"]
    m = lab.platen_mass
    t = (m / (rho * aspect**2)) ** (1 / 3)  # a square steel plate w = aspect·t
    w = aspect * t
    depth = t / 2 if lab.com_height is None else t / 2 + lab.com_height  # c.o.m. above line
    inertia = lab.pitch_inertia or m * (w * w + t * t) / 12
    supply = units.to_si(d["hydraulics"]["supply_pressure_mpa"], "MPa")
    n = lab.n_actuators
    s = lab.servo
    g = TableGeometry(plan_width=w, thickness=t, weight=m * units.G, pitch_inertia=inertia,
                      actuator_line_depth=depth, vertical_square=0.0, stabilizer_square=0.0,
                      horizontal_offset=w / 4 if n > 1 else 0.0, pit_pressure=0.0,
                      foundation_weight=d["foundation"]["mass_over_platen"] * m * units.G,
                      supply_pressure=supply, source=f"{lab.name}: assumed plate")
    specs = TableSpecs(weight_capacity=(lab.payload or m) * units.G, overhead_clearance=None,
                       overturning_capacity=None, stroke_h=lab.stroke, stroke_v=0.0,
                       velocity_h=lab.velocity, velocity_v=0.0,
                       acceleration_h=lab.acceleration, acceleration_v=0.0,
                       bandwidth=(lab.band or (0.0, 100.0))[1], source=lab.name)
    acts = tuple(ActuatorSpec(name=f"H{i}", model="described", area=s.area,
                              stroke=2 * (lab.stroke or 1.0), capacity=supply * s.area,
                              flow=(lab.velocity * s.area if lab.velocity else None))
                 for i in range(1, n + 1))
    none = DirectionSettings(gain=0.0, delta_p=0.0, rate=0.0)
    std = ControlSettings(horizontal=none, pitch=none, vertical=none, roll=none, twist=none)
    table = EERCTable(g, specs, acts, s, std, KnobFactors({}))
    return VirtualTable(table=table, layout=lay, actuators=_actuators(table, lay),
                        horizontal_servo=s, vertical_servo=None, pitch_loop=None,
                        stabilizers=Stabilizers((), 0.0, 0.0, 0.0, 0.0),
                        settings={}, dofs=("x",), knobs=False, valve_lag=lab.valve_time_constant,
                        control=lab.control, name=lab.name, force_measured=lab.force_measured,
                        declared=lab.declared)


def describe(vt: VirtualTable) -> dict[str, Any]:
    """The derived numbers, in the report's units (for notes and the CLI)."""
    s, v = vt.stabilizers, vt.vertical_servo
    return {
        "stabilizer_stiffness_lb_per_in": units.from_si(s.stiffness, "lb/in"),
        "stabilizer_damping_lb_s_per_in": units.from_si(s.damping, "lb-s/in"),
        "stabilizer_volume_in3": units.from_si(s.volume, "in3"),
        "vertical_k_t_in2_per_s": units.from_si(v.k_t, "in2/s"),
        "vertical_volume_in3": units.from_si(v.volume, "in3"),
        "vertical_k_p_in_per_psi": units.from_si(v.k_p, "in/psi"),
        "pitch_loop": {"f_hz": vt.pitch_loop.f_o, "xi": vt.pitch_loop.xi_o,
                       "k_per_s": vt.pitch_loop.k_o},
        "pivot_depth_in": units.from_si(vt.pivot_depth, "in"),
        "slab_pitch_inertia_kip_in_s2": units.from_si(vt.table.geometry.pitch_inertia,
                                                      "kip-in-s2"),
        "slab_mass_kg": vt.table.geometry.mass,
    }
