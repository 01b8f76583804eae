"""The EERC virtual table built from the presets (`virtual_table`): the description the
MJCF builder, the controllers and the analytic and reduced models read
(`vtable.params.virtual.VirtualTable`).

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

from dataclasses import replace
from typing import Any

import numpy as np

from vtable import units
from vtable.analytic.closed_forms import stabilizer_rocking
from vtable.analytic.pitch import pitch_loop
from vtable.analytic.servo import servo_from_open_loop
from vtable.params import presets
from vtable.params.loops import OpenLoop
from vtable.params.table import ServoConstants, TableHardware
from vtable.params.virtual import Actuator, MultibodyLayout, Stabilizers, VirtualTable


def place_actuators(table: TableHardware, lay: MultibodyLayout) -> tuple[Actuator, ...]:
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
                          source="derived: pitch DOF loop = §8.6.2 loop (tables/eerc.py)")
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


def virtual_table(table: TableHardware | None = None,
                  layout: MultibodyLayout | None = None) -> VirtualTable:
    """The EERC virtual table from the presets: the stabilizers carry Table 8.1's rocking
    spring less the pitch loop's (`with_rocking`)."""
    table = table or presets.eerc_table()
    if layout is None:
        layout = MultibodyLayout.from_dict(presets.data("eerc")["multibody"],
                                           "eerc.toml [multibody]")
    g = table.geometry
    pitch = pitch_loop(layout.pitch_loop_f, g.pitch_inertia)
    v1 = table.actuator("V1")
    vert = vertical_servo_for_pitch_loop(pitch, g.pitch_inertia, g.vertical_square / 2, 4,
                                         v1.area, table.servo.beta, layout.vertical_k_ct)
    settings = {k: getattr(table.standard, k) for k in
                ("horizontal", "pitch", "vertical", "roll", "twist")}
    unset = Stabilizers(pairs=(("P1", "P2"), ("P4", "P3")), stiffness=0.0, damping=0.0,
                        volume=0.0, beta=layout.stabilizer_beta)
    vt = VirtualTable(table=table, layout=layout, actuators=place_actuators(table, layout),
                      horizontal_servo=table.servo, vertical_servo=vert, pitch_loop=pitch,
                      stabilizers=unset, settings=settings)
    rock = presets.hybrid_rocking()
    return with_rocking(vt, rock.k_theta, rock.c_theta)


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
