"""A lab's table as every model reads it (`vtable.params.virtual.VirtualTable`), from what
its run files declare (`vtable.runs.lab.lab_table` reads the run format's [table]): the
EERC table with the declaration applied to it, or a uniaxial platen; and the bare table's
loop the declaration implies (`bare_loop`, eq 6.16)."""

from __future__ import annotations

from dataclasses import replace

from vtable import units
from vtable.analytic.servo import open_loop_from_servo
from vtable.errors import VtableError
from vtable.params import presets
from vtable.params.loops import OpenLoop
from vtable.params.table import (
    ActuatorSpec,
    ControlSettings,
    DirectionSettings,
    KnobFactors,
    ServoConstants,
    TableGeometry,
    TableHardware,
    TableSpecs,
)
from vtable.params.virtual import DECLARED, MultibodyLayout, Stabilizers, VirtualTable
from vtable.tables.eerc import place_actuators, virtual_table


def actuator_servo(vt: VirtualTable) -> ServoConstants:
    """One horizontal actuator's constants carrying the platen's mass per horizontal
    actuator (the EERC table's Table B.5 keeps its own fitted mass in the model)."""
    return replace(vt.horizontal_servo, mass=vt.platen_mass / vt.n_actuators)


def bare_loop(vt: VirtualTable) -> OpenLoop:
    """(f_o, ξ_o, k_o) of the bare table's horizontal loop (eq 6.16, with the platen's
    damping; the valve lag is not in eq 6.15): `actuator_servo`'s."""
    return open_loop_from_servo(actuator_servo(vt))


def described_table(*, name: str, dofs: tuple[str, ...], platen_mass: float,
                    pitch_inertia: float | None, com_height: float | None, n_actuators: int,
                    servo: ServoConstants, valve_lag: float, controller: str,
                    control: tuple | None, limits: dict, force_measured: str,
                    declared: dict | None = None) -> VirtualTable:
    """The table a lab's declaration describes (SI; `servo`: one actuator's loop, its mass
    the platen's per actuator; `limits`: stroke, velocity, acceleration, payload, band,
    None where not declared): the EERC table with what the declaration changes of it (its
    mass, pitch inertia and centre-of-mass height, its loop constants, the table's limits —
    its actuators keep Table 2.1's ratings) applied, or a uniaxial platen
    (`uniaxial_table`); the controller's kind and its own terms (a control stage) go with
    it."""
    if name == "eerc" and tuple(dofs) != ("x",):
        vt = virtual_table()
        if servo != replace(vt.horizontal_servo, mass=servo.mass) or \
                abs(platen_mass - vt.platen_mass) > 1e-9 * platen_mass:
            g = replace(vt.table.geometry, mass=platen_mass)
            vt = replace(vt, table=replace(vt.table, geometry=g),
                         horizontal_servo=replace(servo, mass=vt.horizontal_servo.mass))
        if pitch_inertia is not None and pitch_inertia != vt.pitch_inertia:
            g = replace(vt.table.geometry, pitch_inertia=pitch_inertia)
            vt = replace(vt, table=replace(vt.table, geometry=g))
        specs = _specs_changed(vt, limits)
        if specs is not None:
            vt = replace(vt, table=replace(vt.table, specs=specs))
        return replace(vt, valve_lag=valve_lag, force_measured=force_measured,
                       control=control, controller=controller, declared=declared,
                       com_height=com_height)
    if tuple(dofs) != ("x",):
        raise VtableError(f"table {name!r}: the virtual table models the EERC table or a "
                          f"uniaxial platen, not DOFs {', '.join(dofs)}")
    return uniaxial_table(name=name, platen_mass=platen_mass, pitch_inertia=pitch_inertia,
                          com_height=com_height, n_actuators=n_actuators, servo=servo,
                          valve_lag=valve_lag, controller=controller, control=control,
                          limits=limits, force_measured=force_measured, declared=declared)


def _specs_changed(vt: VirtualTable, limits: dict) -> TableSpecs | None:
    """The EERC table's Table 2.2 limits with those a declaration changes, or None."""
    now = {"stroke": vt.stroke, "velocity": vt.velocity, "acceleration": vt.acceleration,
           "payload": vt.payload, "band": vt.band}
    if all(limits.get(k) == v for k, v in now.items()):
        return None
    return replace(vt.table.specs, **_spec_values(limits), source=DECLARED)


def _spec_values(limits: dict) -> dict:
    """TableSpecs' horizontal limits from a declaration's (None stays None: not declared)."""
    band, payload = limits.get("band"), limits.get("payload")
    return {"stroke_h": limits.get("stroke"), "velocity_h": limits.get("velocity"),
            "acceleration_h": limits.get("acceleration"),
            "weight_capacity": None if payload is None else payload * units.G,
            "bandwidth": None if band is None else band[1],
            "band_low": 0.0 if band is None else band[0]}


def uniaxial_table(*, name: str, platen_mass: float, pitch_inertia: float | None,
                   com_height: float | None, n_actuators: int, servo: ServoConstants,
                   valve_lag: float, controller: str, control: tuple | None, limits: dict,
                   force_measured: str, declared: dict | None = None) -> VirtualTable:
    """A platen on a slide in x driven by its horizontal actuators (lumped or several, side
    by side), their loop from the lab's description, physical gains (no knobs). The shape
    the description does not give — a steel plate of the platen's mass, the actuators' pin
    lengths — comes from params/data/uniaxial_multibody.toml (each number marked assumed);
    a limit not declared is absent (None)."""
    d = presets.data("uniaxial_multibody")
    lay = MultibodyLayout.from_dict(d["layout"], "uniaxial_multibody.toml [layout]")
    rho, aspect = d["plate"]["density_kg_m3"], d["plate"]["width_over_thickness"]
    m = platen_mass
    t = (m / (rho * aspect**2)) ** (1 / 3)  # a square steel plate w = aspect·t
    w = aspect * t
    depth = t / 2 if com_height is None else t / 2 + com_height  # c.o.m. above line
    inertia = pitch_inertia or m * (w * w + t * t) / 12
    supply = units.to_si(d["hydraulics"]["supply_pressure_mpa"], "MPa")
    n = n_actuators
    s = servo
    g = TableGeometry(plan_width=w, thickness=t, mass=m, pitch_inertia=inertia,
                      actuator_line_depth=depth, vertical_square=0.0, stabilizer_square=0.0,
                      horizontal_offset=w / 4 if n > 1 else 0.0, pit_pressure=0.0,
                      foundation_weight=d["foundation"]["mass_over_platen"] * m * units.G,
                      supply_pressure=supply, source=f"{name}: assumed plate")
    specs = TableSpecs(overhead_clearance=None, overturning_capacity=None, stroke_v=0.0,
                       velocity_v=0.0, acceleration_v=0.0, source=name, **_spec_values(limits))
    velocity, stroke = limits.get("velocity"), limits.get("stroke")
    acts = tuple(ActuatorSpec(name=f"H{i}", model="described", area=s.area,
                              stroke=2 * stroke if stroke else None, capacity=supply * s.area,
                              flow=(velocity * s.area if velocity else None))
                 for i in range(1, n + 1))
    none = DirectionSettings(gain=0.0, delta_p=0.0, rate=0.0)
    std = ControlSettings(horizontal=none, pitch=none, vertical=none, roll=none, twist=none)
    table = TableHardware(g, specs, acts, s, std, KnobFactors({}))
    return VirtualTable(table=table, layout=lay, actuators=place_actuators(table, lay),
                        horizontal_servo=s, vertical_servo=None, pitch_loop=None,
                        stabilizers=Stabilizers((), 0.0, 0.0, 0.0, 0.0),
                        settings={}, dofs=("x",), knobs=False, valve_lag=valve_lag,
                        control=control, controller=controller, name=name,
                        force_measured=force_measured,
                        declared=declared)
