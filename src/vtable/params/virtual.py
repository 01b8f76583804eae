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

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from vtable import units
from vtable.errors import VtableError
from vtable.params.base import Params, plain, quantity
from vtable.params.loops import OpenLoop
from vtable.params.table import DirectionSettings, EERCTable, ServoConstants


@dataclass(frozen=True)
class MultibodyLayout(Params):
    """Layout assumptions of the multibody table (eerc.toml [multibody])."""

    rib_width: float = quantity("in", "rib_width_in", minimum=0)
    rib_depth: float = quantity("in", "rib_depth_in", minimum=0)
    rib_offset: float = quantity("in", "rib_offset_in", minimum=0, exclusive=False)
    horizontal_length: float = quantity("in", "horizontal_length_in", minimum=0)
    vertical_length: float = quantity("in", "vertical_length_in", minimum=0)
    stabilizer_length: float = quantity("in", "stabilizer_length_in", minimum=0)
    stabilizer_beta: float = quantity("psi", "stabilizer_beta_psi", minimum=0)
    vertical_k_ct: float = quantity("in3/s/psi", "vertical_k_ct_in3_per_s_per_psi", minimum=0,
                                    exclusive=False)
    pitch_loop_f: float = quantity("Hz", "pitch_loop_f_hz", minimum=0)
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
    vertical_servo: ServoConstants  # derived (module docstring), per vertical actuator
    pitch_loop: OpenLoop  # §8.6.2 target of the vertical calibration
    stabilizers: Stabilizers
    settings: dict[str, DirectionSettings]

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
        the knob factors (Tables B.1-B.4 plus the [multibody] assumptions)."""
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
    for name, y in (("H1", g.horizontal_offset), ("H2", 0.0), ("H3", -g.horizontal_offset)):
        spec = table.actuator(name)
        out.append(Actuator(name, "horizontal", (-half, y, line),
                            (-half - lay.horizontal_length, y, line),
                            spec.area, spec.stroke, spec.capacity, spec.flow))
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
    """Per-actuator constants whose pitch DOF loop is `ol` (eq 6.16 solved for k_t, V, k_p
    with k_v = 0): m = I/(n·lever²), k = k_o A, V = 4βA²/(m ω_o²),
    k_f = (2ξ_o A/(m ω_o) - k_c)/k."""
    m = inertia / (n * lever**2)
    k = ol.k_o * area
    V = 4 * beta * area**2 / (m * ol.omega_o**2)
    k_f = (2 * ol.xi_o * area / (m * ol.omega_o) - k_ct / area) / k
    if k_f < 0:
        raise VtableError("vertical-valve leakage alone gives more pitch damping than the "
                          "§8.6.2 loop; lower vertical_k_ct")
    return ServoConstants(k_p=k_f * area, k_t=k, k_ct=k_ct, rc=0.01, mass=m, beta=beta,
                          area=area, volume=V, k_v=0.0,
                          source="derived: pitch DOF loop = §8.6.2 loop (params/virtual.py)")


def split_rocking(k_theta: float, c_theta: float, vt: VirtualTable) -> tuple[float, float]:
    """Per-piston stabilizer stiffness and damping so that, with the pitch loop of the
    vertical actuators, the table's rocking spring and dashpot at the §8.6.3 coupled
    frequency (2.58 Hz) are k_θ and c_θ (eqs 8.32-8.33, 8.4)."""
    from vtable.analytic.closed_forms import feedback_spring
    from vtable.params import presets

    f_c = presets._file("models")["section8_6_2"]["f_coupled_hz"]
    g = vt.table.geometry
    k_v, c_v = feedback_spring(g.pitch_inertia, vt.pitch_loop, f_c)
    d_p = g.stabilizer_square
    k, c = (k_theta - float(k_v)) / d_p**2, (c_theta - float(c_v)) / d_p**2
    if k <= 0 or c < 0:
        raise VtableError(f"rocking spring {k_theta:.3g} N m/rad is weaker than the vertical "
                          f"actuators' pitch loop alone ({float(k_v):.3g})")
    return k, c


def with_rocking(vt: VirtualTable, k_theta: float, c_theta: float) -> VirtualTable:
    """The table with its stabilizers retuned to a rocking spring/dashpot (k_θ, c_θ)."""
    k, c = split_rocking(k_theta, c_theta, vt)
    a_p = vt.table.actuator("P1").area
    s = vt.stabilizers
    return replace(vt, stabilizers=replace(s, stiffness=k, damping=c,
                                           volume=2 * s.beta * a_p**2 / k))


def virtual_table(table: EERCTable | None = None,
                  layout: MultibodyLayout | None = None) -> VirtualTable:
    """The EERC virtual table from the presets."""
    from vtable.analytic.closed_forms import feedback_spring, pitch_loop_from_springs
    from vtable.params import presets

    table = table or presets.eerc_table()
    if layout is None:
        layout = MultibodyLayout.from_dict(presets._file("eerc")["multibody"],
                                           "eerc.toml [multibody]")
    acts = _actuators(table, layout)
    g = table.geometry
    d = presets._file("models")["section8_6_2"]
    k_v = units.to_si(d["k_v_lb_in_per_rad"], "lb-in/rad")
    c_v = units.to_si(d["c_v_lb_in_s_per_rad"], "lb-in-s/rad")
    f_c = d["f_coupled_hz"]
    rock = presets.hybrid_rocking()
    pitch = pitch_loop_from_springs(k_v, c_v, f_c, layout.pitch_loop_f, g.pitch_inertia)
    k_vc, c_vc = feedback_spring(g.pitch_inertia, pitch, f_c)
    # stabilizers: k_p = k_θ - k_v(ω_c) = (F/Δx) d_p² (eq 8.4), F/Δx = 2β A²/V (eq 8.3)
    d_p = g.stabilizer_square
    k_piston = (rock.k_theta - float(k_vc)) / d_p**2
    c_piston = (rock.c_theta - float(c_vc)) / d_p**2
    a_p = table.actuator("P1").area
    if k_piston <= 0 or c_piston < 0:
        raise VtableError("Table 8.1 rocking spring is weaker than the pitch loop's alone")
    stab = Stabilizers(pairs=(("P1", "P2"), ("P4", "P3")), stiffness=k_piston,
                       damping=c_piston, volume=2 * layout.stabilizer_beta * a_p**2 / k_piston,
                       beta=layout.stabilizer_beta)
    v1 = table.actuator("V1")
    vert = vertical_servo_for_pitch_loop(pitch, g.pitch_inertia, g.vertical_square / 2, 4,
                                         v1.area, table.servo.beta, layout.vertical_k_ct)
    settings = {k: getattr(table.standard, k) for k in
                ("horizontal", "pitch", "vertical", "roll", "twist")}
    return VirtualTable(table=table, layout=layout, actuators=acts,
                        horizontal_servo=table.servo, vertical_servo=vert, pitch_loop=pitch,
                        stabilizers=stab, settings=settings)


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
