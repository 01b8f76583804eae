"""What an effect may know of the run's table (`Assembly.table`): the platen, the
horizontal actuators, the limits — read from the model's `VirtualTable`, never a preset,
so an effect is right on any table."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

from vtable import units
from vtable.tables.eerc import virtual_table


@dataclass(frozen=True)
class TableView:
    """The run's table, SI (see the module docstring)."""

    name: str
    platen_mass: float  # kg
    foundation_mass: float  # kg: the reaction mass (§2.2)
    horizontal: tuple[str, ...]  # the horizontal actuators' names
    piston_area: float  # m²: one horizontal actuator of the model
    stroke: float | None  # m: one horizontal actuator's stroke (None: not declared)
    capacity: float  # N: one horizontal actuator's force capacity
    rated_flow: float  # m³/s: one horizontal servovalve's rated flow (0: not given)
    velocity_limit: float | None  # m/s: the table's horizontal velocity limit (None: none)
    supply_pressure: float  # Pa
    rc: float  # s: the RC filter of the ΔP feedback (eq B.4)
    #: what a campaign's runs show of the effects' parameters (`Effect.evidence`): effect ->
    #: ({parameter: value in its units}, where from); the diagnosis's prior is centred there
    evidence: dict = field(default_factory=dict, compare=False, hash=False)

    @property
    def n_horizontal(self) -> int:
        return len(self.horizontal)

    @classmethod
    def of(cls, vt, piston_area: float | None = None) -> TableView:
        """The view of the virtual table `vt` (`piston_area`: the model's, if not the
        table's)."""
        g = vt.table.geometry
        acts = vt.group("horizontal")
        a = acts[0]
        return cls(name=vt.name, platen_mass=g.mass, foundation_mass=g.foundation_weight / units.G,
                   horizontal=tuple(x.name for x in acts),
                   piston_area=piston_area or a.area, stroke=a.stroke, capacity=a.capacity,
                   rated_flow=a.flow or 0.0, velocity_limit=vt.table.specs.velocity_h,
                   supply_pressure=g.supply_pressure,
                   rc=vt.horizontal_servo.rc or vt.table.servo.rc)


@cache
def eerc() -> TableView:
    """The EERC table's view: where the catalog's table-dependent defaults are declared."""
    return TableView.of(virtual_table())
