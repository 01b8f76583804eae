"""The table vtable models for a run's declared table (`vtable.runs.lab.LabTable`): the
EERC table itself, its description applied to it, or a uniaxial platen."""

from __future__ import annotations

from dataclasses import replace

from vtable import units
from vtable.errors import VtableError
from vtable.params import presets
from vtable.params.table import (
    ActuatorSpec,
    ControlSettings,
    DirectionSettings,
    EERCTable,
    KnobFactors,
    TableGeometry,
    TableSpecs,
)
from vtable.params.virtual import MultibodyLayout, Stabilizers, VirtualTable
from vtable.tables.eerc import place_actuators, virtual_table


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
    return VirtualTable(table=table, layout=lay, actuators=place_actuators(table, lay),
                        horizontal_servo=s, vertical_servo=None, pitch_loop=None,
                        stabilizers=Stabilizers((), 0.0, 0.0, 0.0, 0.0),
                        settings={}, dofs=("x",), knobs=False, valve_lag=lab.valve_time_constant,
                        control=lab.control, name=lab.name, force_measured=lab.force_measured,
                        declared=lab.declared)
