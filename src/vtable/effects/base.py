"""What an effect is: a named piece of physics with typed parameters that knows how it
enters each model of the table.

An `Effect` says, in words, what it is (`physics`), where the report treats it
(`section`) and how it shows in measured runs (`signature`); declares its parameters
(`Param`: unit, bounds, default and where the default comes from, fitted on a log scale
or not); and enters a model through `apply(m, p)`, where `m` is an assembly — the reduced
model the diagnosis fits (`vtable.models.reduced.ReducedAssembly`) or the multibody
virtual table (`vtable.models.virtual.VirtualAssembly`) — and `p` its parameters in SI.
Both assemblies speak the same small vocabulary (`Assembly`), so an effect is usually
written once; one that needs to differ overrides `reduced(m, p)` or `virtual(v, p)`.

A user's effect is the same: a subclass in a file of theirs, registered with
`vtable.effects.register` (see the README).
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol

from vtable import units
from vtable.effects.table import eerc
from vtable.errors import VtableError, did_you_mean


class Param:
    """A parameter of an effect, in the unit its users think in (`unit`, a key of
    `vtable.units.UNITS`). `default` may be a callable: of no argument (evaluated when
    first needed), or of the run's table (`table.TableView` -> value), resolved on the
    model's table when the effect is applied (`default` itself is the EERC table's);
    `source` says where the default comes from. A `discrete` parameter takes whole values
    from `lower` to `upper` (which storey, say): the fit tries each value the model can be
    built with and keeps the best, rather than moving it by least squares. `spread` is
    the factor from the default that counts as one σ of the diagnosis's prior on a log
    parameter (`vtable.diagnose.selection.PLAUSIBLE` when None): wide for a parameter
    whose typical value varies over decades from specimen to specimen."""

    def __init__(self, name: str, unit: str, default: float | Callable[..., float],
                 lower: float, upper: float, log: bool = False, source: str = "",
                 doc: str = "", discrete: bool = False, spread: float | None = None) -> None:
        # (a unit in another spelling, m/s^2, is kept in the spelling of `UNITS`, m/s2)
        self.name, self.unit, self.lower, self.upper = name, units.canonical(unit), lower, upper
        self.log, self.source, self.doc, self.discrete = log, source, doc, discrete
        self.spread = spread
        self._default = default
        self._of_table: Callable | None = None
        if callable(default) and len(inspect.signature(default).parameters) == 1:
            self._of_table = default

    @property
    def on_table(self) -> bool:
        """Whether the default depends on the run's table."""
        return self._of_table is not None

    @property
    def default(self) -> float:
        if callable(self._default):
            if self._of_table is not None:
                self._default = float(self._of_table(eerc()))
            else:
                self._default = float(self._default())
        return self._default

    def default_on(self, table) -> float:
        """The default on `table` (a `table.TableView`)."""
        d = self.default
        return float(self._of_table(table)) if self._of_table is not None else d

    def check_declaration(self, where: str) -> None:
        """The declaration itself is sound (a user's effect is checked on loading)."""
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise VtableError(f"{where}: parameter name {self.name!r} is not an identifier")
        if not units.known(self.unit):
            raise VtableError(f"{where}: parameter {self.name!r} has unknown unit "
                              f"{self.unit!r}")
        for k in ("lower", "upper"):
            v = getattr(self, k)
            if not isinstance(v, int | float) or isinstance(v, bool) or not math.isfinite(v):
                raise VtableError(f"{where}: parameter {self.name!r} needs a finite {k} "
                                  f"bound, got {v!r}")
        if self.spread is not None and (not self.log or not isinstance(self.spread, int | float)
                                        or not self.spread > 1):
            raise VtableError(f"{where}: parameter {self.name!r}: spread {self.spread!r} needs "
                              "a log parameter and a factor above 1")
        if not self.lower < self.upper:
            raise VtableError(f"{where}: parameter {self.name!r}: lower bound {self.lower:g} is "
                              f"not below the upper bound {self.upper:g}")
        if self.discrete and (self.log or any(float(v) != int(v) for v in (self.lower,
                                                                            self.upper))):
            raise VtableError(f"{where}: parameter {self.name!r} is discrete: it needs whole "
                              "bounds and a linear scale")
        if self.log and self.lower <= 0:
            raise VtableError(f"{where}: parameter {self.name!r} is fitted on a log scale, so "
                              f"its lower bound must be > 0, got {self.lower:g}")
        d = self.default
        if not isinstance(d, int | float) or not math.isfinite(d) or \
                not self.lower <= d <= self.upper:
            raise VtableError(f"{where}: parameter {self.name!r} default {d!r} is outside its "
                              f"bounds [{self.lower:g}, {self.upper:g}] {self.unit}")

    def to_si(self, v: float) -> float:
        return float(units.to_si(v, self.unit))

    def __repr__(self) -> str:
        return (f"Param({self.name!r}, {self.unit!r}, default={self.default:g}, "
                f"[{self.lower:g}, {self.upper:g}]{', log' if self.log else ''})")


class Assembly(Protocol):
    """The vocabulary both models speak, each verb realised by both (`ReducedAssembly`,
    `VirtualAssembly`); an effect's `apply` may call these only, which `register` checks.
    Coordinates are named: "x" (the platen), "pitch" once freed, the specimen's storeys
    ("x_s", "x_s1", ...; the virtual table's joints of the same names) and added DOFs.

    Lengths, forces, masses in SI.
    """

    vt: Any  # the table's parameters (`VirtualTable`)
    table: Any  # what an effect reads of the run's table (`vtable.effects.table.TableView`)
    specimen: Any
    #: the structures effects have stood on the platen (`add_structure`): (coordinate,
    #: mass kg, stiffness N/m, damping N·s/m) each, for effects acting on the structure
    structures: list

    def add_stage(self, stage: Any, **params: float) -> None:
        """A stage of the horizontal actuators' hydraulic element
        (`vtable.hydraulics.stage.Stage`: valve, flow, pressure, feedback or force law)
        with its named parameters (SI, one actuator's)."""

    def add_dof(self, name: str, mass: float) -> None:
        """A new coordinate: a mass `name` (kg) sliding in x, held by nothing until a
        spring, a force or the actuators tie it."""

    def add_spring(self, a: str, b: str | None, stiffness: float, damping: float) -> None:
        """A spring and dashpot (N/m, N s/m) between coordinates a and b (None: ground)."""

    def add_structure(self, name: str, mass: float, stiffness: float, damping: float) -> None:
        """A structure nobody declared standing on the platen: a mass `name` (kg) on a
        spring and dashpot (N/m, N s/m) to "x", listed in `structures` so that an effect
        acting on the specimen's structure (a degradation) finds it."""

    def set_actuator(self, moving: str | None = None, reaction: str | None = None) -> None:
        """What the horizontal actuators push (`moving`) and react on (`reaction`)."""

    def add_force(self, law: Callable, a: str, b: str | None = None,
                  params: Sequence[float] = (), states: int = 0, mass: float = 0.0,
                  stiffness: float | None = None) -> None:
        """A force `law(d, v, z, p, dz)` on coordinate a and its reaction on b (d, v: the
        relative motion a - b); `stiffness` and `mass` as for `insert_at_actuators`."""

    def unlock(self, dof: str) -> None:
        """Let the platen move in a DOF the base model holds fixed (e.g. "pitch")."""

    def set_rocking(self, k_theta: float, c_theta: float) -> None:
        """The platen's rocking spring and dashpot (N m/rad, N m s/rad): the passive
        stabilizers and the vertical actuators' pitch loop together (eqs 8.32-8.33)."""

    def add_reaction_mass(self, name: str, mass: float, stiffness: float,
                          damping: float) -> None:
        """The horizontal actuators react on a mass sprung to the ground."""

    def insert_at_actuators(self, name: str, mass: float, law: Callable, params: Sequence[float],
                            states: int = 0, stiffness: float | None = None) -> None:
        """A mass between the horizontal actuators and the platen, tied to the platen by
        `law(d, v, z, p, dz) -> force on the mass` (d, v: its travel relative to the
        platen, z its `states` state variables with rates written to dz). `stiffness` (N/m)
        is the law's largest slope: both models step finely enough for the stiff mode it
        makes with `mass`; left out, it is worked out from the law (`stiffness.slope`)."""

    def add_storey_force(self, law: Callable, params: Sequence[float], states: int = 0,
                         stiffness: float | None = None) -> None:
        """A force `law(d, v, z, p, dz)` on every storey of the specimen (d, v: drift)."""

    def add_storey_quadratic_damper(self, c2: float) -> None:
        """F = -c₂|v|v on every storey's drift velocity."""

    def add_output_filter(self, fn: Callable[[Any, float], Any],
                          channels: Sequence[str] | None = None) -> None:
        """`fn(x, fs) -> x` applied to every measured response channel (sampled at fs), or
        to those named in `channels` only (e.g. an accelerometer's mount)."""


class Effect:
    """Base class of the catalog's and users' effects (see the module docstring)."""

    name: str = ""
    physics: str = ""
    section: str = ""
    signature: str = ""
    params: tuple[Param, ...] = ()
    #: what the effect models builds up over a run (a specimen that degrades): a fit of a
    #: model holding it trains on the whole first 60 % of every run, not only its first
    #: `vtable.diagnose.sampling.TRAIN_MAX_S`, since the change grows with the run's length
    accumulates: bool = False
    #: the hydraulic stages (`vtable.hydraulics.stage.Stage`) `apply` may add: a catalog
    #: effect's ride, switched off, in every nonlinear reduced model's compiled element
    #: (`vtable.effects.registry.stock_stages`, read from the catalog's effects only), so
    #: that models with and without it share one integrator; a user's stage is compiled
    #: into each set of stages it joins, whatever this says
    stages: tuple = ()

    def apply(self, m: Assembly, p: dict[str, float]) -> None:
        raise NotImplementedError(f"{type(self).__name__} must define apply(m, p)")

    def reduced(self, m: Assembly, p: dict[str, float]) -> None:
        """How the effect enters the reduced model (default: `apply`)."""
        self.apply(m, p)

    def virtual(self, v: Assembly, p: dict[str, float]) -> None:
        """How the effect enters the virtual table (default: `apply`)."""
        self.apply(v, p)

    def unsupported(self, campaign: Any) -> str | None:
        """Why the campaign's runs themselves hold nothing this effect could fit, or None
        (the default). Such an effect is not tried in a diagnosis (the round lists it
        under `skipped` with this reason). `campaign` is the diagnosis's prepared campaign
        (`vtable.diagnose.campaign.Campaign`: its runs and the checks made on them)."""
        return None

    def evidence(self, campaign: Any) -> tuple[dict[str, float], str] | None:
        """What the campaign's runs themselves show of this effect's parameters, measured
        before any fit (identification, the checks on the runs): (values in the
        parameters' units, where they come from), or None (the default). A diagnosis
        starts the effect's fit there too and centres its prior on them instead of the
        defaults (`vtable.diagnose.selection.implausibility`): what a run shows is not
        charged as implausible. Values outside a parameter's bounds are held at them."""
        return None

    def choices(self, specimen: Any, tried: Sequence[tuple[dict[str, float], float]] = ()
                ) -> list[dict[str, float]] | None:
        """The combinations of the effect's discrete parameters (`Param(discrete=True)`) a
        fit tries next on `specimen`, each {name: whole value}, given those `tried` so far
        ((combination, training cost) each; none at first); an empty list: no more. None
        (the default): every combination of their ranges at first, those the model cannot
        be built with skipped."""
        return None

    def unseen(self, values: dict[str, float],
               predictions: Mapping[str, Mapping[str, Any]]) -> str | None:
        """Why the effect at its fitted `values` (its units) does not act in the fitted
        model's own predictions of the runs (run -> channel -> SI array), or None (the
        default). A reason flags the candidate (`vtable.diagnose.selection`, criterion 5):
        its fit extrapolated beyond what the runs reach, so it is not added on that
        evidence."""
        return None

    # -- parameters ----------------------------------------------------------------------
    def param(self, name: str) -> Param:
        for q in self.params:
            if q.name == name:
                return q
        raise VtableError(f"{self.name}: no parameter {name!r}; it has "
                          f"{', '.join(q.name for q in self.params) or 'none'}")

    def defaults(self) -> dict[str, float]:
        return {q.name: q.default for q in self.params}

    def check(self, values: dict[str, float], where: str = "") -> dict[str, float]:
        """Fill defaults; an unknown name or a value outside its bounds is an error."""
        where = where or self.name
        known = {q.name: q for q in self.params}
        for k in values:
            if k not in known:
                raise VtableError(f"{where}: unknown parameter {k!r}"
                                  f"{did_you_mean(k, known)}; expected "
                                  f"{', '.join(known) or 'none'}")
        out = self.defaults() | dict(values)
        for k, v in out.items():
            q = known[k]
            if not (isinstance(v, int | float) and math.isfinite(v) and q.lower <= v <= q.upper):
                raise VtableError(f"{where}: {k} = {v:g} {q.unit} is outside "
                                  f"[{q.lower:g}, {q.upper:g}]")
            if q.discrete and v != int(v):
                raise VtableError(f"{where}: {k} = {v:g} must be a whole number")
        return out

    def si(self, values: dict[str, float]) -> dict[str, float]:
        """Parameter values (the effect's units) in SI."""
        return {k: self.param(k).to_si(v) for k, v in values.items()}

    def __repr__(self) -> str:
        return f"<effect {self.name}>"
