"""`Physics`: what a model of the table contains — the base (the horizontal servo loop as
open-loop parameters on the bare table, the specimen) and the effects with their
parameters (each effect's own units). The reduced model and the virtual table both
realise it: the base through their assemblies, each effect through its own hooks."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from vtable.analytic.hysteresis import add_specimen_hysteresis
from vtable.analytic.servo import open_loop_from_servo, servo_from_open_loop
from vtable.effects.registry import get
from vtable.errors import VtableError
from vtable.params.loops import OpenLoop
from vtable.params.specimen import OpenSeesSpecimen, Specimen
from vtable.params.table import ServoConstants
from vtable.params.virtual import VirtualTable
from vtable.tables.eerc import virtual_table


class Checked(dict):
    """A `Physics`'s effects as checked (`Effect.check`: every parameter present and within
    its bounds), passed on unchanged by `dataclasses.replace` of another field: a fit sets
    a parameter hundreds of times, and the effects need not be checked again each time (a
    new dict, as `with_effect` and a fitted effect parameter make, is). Checked against the
    effects registered when it was made."""

    __slots__ = ()


@dataclass(frozen=True)
class Physics:
    """Base model plus effects {name: {param: value in the effect's units}}."""

    open_loop: OpenLoop
    specimen: Specimen
    effects: dict[str, dict[str, float]] = field(default_factory=dict)
    #: calibrated table values replacing the declared ones (SI): platen_mass (kg),
    #: com_height (m above the actuator line), pitch_inertia (kg m²), and the declared
    #: controller's stage parameters as "control.NAME" (`ControlUse.calibrated`)
    table: dict[str, float] = field(default_factory=dict)
    #: (effect, parameter) -> the value a table-dependent default was filled with (the
    #: EERC table's): still that value when applied, it is the run's table's default
    defaulted: dict = field(default_factory=dict, compare=False, repr=False)
    #: the specimen in each further state of a campaign ([specimen] state): state name ->
    #: its specimen; `specimen` is the state `base_state`'s (the table and the effects are
    #: shared)
    states: dict[str, Specimen] = field(default_factory=dict)
    base_state: str | None = None
    #: what the horizontal force channels measure ("load_cell" or "delta_p") where the
    #: runs leave it undeclared and a diagnosis found it (`diagnose.reading`); None: the
    #: table's (`VirtualTable.force_measured`)
    force_measured: str | None = None

    def __post_init__(self) -> None:
        if type(self.effects) is Checked:  # another model's, checked: nothing to fill
            return
        checked = Checked({name: get(name).check(p, name) for name, p in self.effects.items()})
        filled = dict(self.defaulted)
        for name, p in self.effects.items():
            for q in get(name).params:
                if q.on_table and q.name not in p:
                    filled[(name, q.name)] = checked[name][q.name]
        object.__setattr__(self, "effects", checked)
        object.__setattr__(self, "defaulted", filled)

    def has(self, name: str) -> bool:
        return name in self.effects

    def with_effect(self, name: str, params: dict[str, float] | None = None) -> Physics:
        return dataclasses.replace(self, effects={**self.effects, name: dict(params or {})})

    def in_state(self, state: str | None) -> Physics:
        """This model with the specimen of `state`: itself for `base_state`, for None and
        for any state when it holds one specimen; one of `states` else (a state it does
        not hold is an error naming those it does)."""
        if state is None or state == self.base_state or not self.states:
            return self
        if state not in self.states:
            held = ", ".join(repr(s) for s in (self.base_state, *self.states))
            raise VtableError(f"the model holds no specimen for state {state!r} (it holds "
                              f"{held}): fit it on runs of that state")
        return dataclasses.replace(self, specimen=self.states[state], states={},
                                   base_state=state)

    def without(self, name: str) -> Physics:
        return dataclasses.replace(self, effects={k: v for k, v in self.effects.items()
                                                  if k != name})

    def on_table(self, vt: VirtualTable) -> VirtualTable:
        """`vt` with this model's calibrated table values (the base servo constants follow
        through `base_hydraulics`: eq 6.16 with the calibrated mass), and the force
        channels' reading when this model holds one."""
        if self.force_measured is not None and self.force_measured != vt.force_measured:
            vt = dataclasses.replace(vt, force_measured=self.force_measured)
        if not self.table:
            return vt
        t = self.table
        ctl = {k.removeprefix("control."): v for k, v in t.items() if k.startswith("control.")}
        if ctl and vt.control is not None:
            vt = dataclasses.replace(vt, control=vt.control._replace(
                params={**vt.control.params, **ctl}))
        g = vt.table.geometry
        g = dataclasses.replace(g, mass=t.get("platen_mass", g.mass),
                                pitch_inertia=t.get("pitch_inertia", g.pitch_inertia))
        return dataclasses.replace(vt, table=dataclasses.replace(vt.table, geometry=g),
                                   com_height=t.get("com_height", vt.com_height))

    def si(self, name: str) -> dict[str, float]:
        """An effect's parameters in SI."""
        return get(name).si(self.effects[name])

    def values_on(self, name: str, table) -> dict[str, float]:
        """An effect's parameters (its units), a table-dependent default left at the EERC
        table's value taken on `table` (`vtable.effects.table.TableView`) instead."""
        e, out = get(name), dict(self.effects[name])
        for k, v in out.items():
            if self.defaulted.get((name, k)) == v:
                out[k] = e.param(k).default_on(table)
        return out

    def apply(self, assembly, model: str) -> None:
        """The specimen's declared yielding storeys (`analytic.hysteresis`) or OpenSees model,
        then every
        effect through its hook for `model` ("reduced" or "virtual"), its table-dependent
        defaults on the assembly's table."""
        add_specimen_hysteresis(assembly, self.specimen)
        if isinstance(self.specimen, OpenSeesSpecimen):
            assembly.add_opensees(self.specimen)
        for name in self.effects:
            e = get(name)
            getattr(e, model)(assembly, e.si(self.values_on(name, assembly.table)))

    @property
    def label(self) -> str:
        return " + ".join(["base", *self.effects])


def per_actuator_template(vt: VirtualTable) -> ServoConstants:
    """Table B.5's constants with the table mass per horizontal actuator (eq 6.16's m)."""
    n = len(vt.group("horizontal"))
    return dataclasses.replace(vt.horizontal_servo, mass=vt.table.geometry.mass / n)


def nominal_open_loop(vt: VirtualTable | None = None) -> OpenLoop:
    """The bare-table loop implied by Table B.5 (eq 6.16 with the table mass per
    actuator): the declared value of the base parameters."""
    return open_loop_from_servo(per_actuator_template(vt or virtual_table()))


def base_hydraulics(ph: Physics, vt: VirtualTable) -> ServoConstants:
    """One horizontal actuator's constants for the base loop (eq 6.16 inverted from the
    open loop; no RC filter, no stage: those are effects, and a lab table's valve lag is
    added by the assemblies)."""
    c = servo_from_open_loop(ph.open_loop, per_actuator_template(vt))
    return dataclasses.replace(c, rc=0.0)


def check_dof(vt: VirtualTable, dof: str) -> None:
    """A platen motion an effect unlocks must be one the run's table has (both models'
    `unlock`)."""
    if dof not in vt.dofs:
        raise VtableError(f"the {vt.name} table's platen has no {dof} motion "
                          f"(its DOFs: {', '.join(vt.dofs)})")
