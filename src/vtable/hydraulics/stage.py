"""A stage of the hydraulic element: one scalar law in the servo-hydraulic actuator's
signal path, with named parameters, that an effect adds (`Assembly.add_stage`).

The element (`element`, eqs 6.1-6.4) carries the drive u of the DOF law to a force on
the platen through six places a stage may sit, in this order:

========  ==========================================  =====================================
kind      law (scalars; ``p`` the named parameters)   where
========  ==========================================  =====================================
control   ``law(u, xc, x, v, z, p, dz) -> u``         the controller's terms beyond eqs
                                                      6.1-6.4 (integral, derivative,
                                                      feedforward, notches, states z): u the
                                                      P law's drive per unit gain, x_c the
                                                      DOF command, x, v the feedback
valve     ``law(q, z, p, dz) -> q``                   the commanded flow k_t·u to the valve
                                                      flow (spool dynamics, states z)
flow      ``law(q, P, p) -> q``                       the valve flow at load pressure P
                                                      (orifice law, rated flow, overlap)
pressure  ``law(beta, P, p) -> beta``                 the oil column's bulk modulus at P
                                                      (entrained air)
feedback  ``law(P, z, p) -> P_f`` and                 the pressure the ΔP feedback reads
          ``rate(P, dP, z, p, dz)``                   (filters; P_f may not depend on Ṗ)
force     ``law(F, v, p) -> F``                       the force A·P on the platen at the
                                                      piston velocity v (friction)
========  ==========================================  =====================================

Laws are plain Python that numba compiles (`compose`): ``p`` is a named tuple
(``p.tau``), ``z``/``dz`` the stage's own states and their rates. A stage declares whether
it is linear in its inputs and states: a model whose stages are all linear is stepped
exactly (state space), otherwise by RK4.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass

from vtable.errors import VtableError

KINDS = ("control", "valve", "flow", "pressure", "feedback", "force")
#: each kind's law signature (the names say what the element passes)
SIGNATURES = {"control": ("u", "xc", "x", "v", "z", "p", "dz"),
              "valve": ("q", "z", "p", "dz"), "flow": ("q", "P", "p"),
              "pressure": ("beta", "P", "p"), "feedback": ("P", "z", "p"),
              "force": ("F", "v", "p")}


@dataclass(frozen=True, eq=False)
class Stage:
    """One stage (see the module docstring): `params` its parameters' names (SI), `states`
    its state count, `linear` whether its law is linear; `order` places it among the
    stages of its kind (lower first; e.g. a spool overlap acts before the rated-flow cap);
    `extensive` names the parameters that add over actuators lumped into one."""

    name: str
    kind: str
    law: Callable
    params: tuple[str, ...]
    states: int = 0
    linear: bool = False
    rate: Callable | None = None
    order: float = 0.0
    #: parameters that add when actuators act together as one (flows, forces)
    extensive: tuple[str, ...] = ()
    #: each state's unit (`vtable.units`; empty: "1", states of mixed or no dimension)
    state_units: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        where = f"stage {self.name!r}"
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise VtableError(f"{where}: a stage name must be an identifier")
        if self.kind not in KINDS:
            raise VtableError(f"{where}: kind {self.kind!r} is not one of {', '.join(KINDS)}")
        if not callable(self.law):
            raise VtableError(f"{where}: law must be a function")
        n = len(inspect.signature(self.law).parameters)
        if n != len(SIGNATURES[self.kind]):
            raise VtableError(f"{where}: a {self.kind} law takes "
                              f"({', '.join(SIGNATURES[self.kind])}), not {n} arguments")
        for k in self.params:
            if not isinstance(k, str) or not k.isidentifier():
                raise VtableError(f"{where}: parameter name {k!r} is not an identifier")
        if (self.kind == "feedback") != (self.rate is not None):
            raise VtableError(f"{where}: a feedback stage (and only it) has a rate(P, dP, z, "
                              "p, dz)")
        if set(self.extensive) - set(self.params):
            raise VtableError(f"{where}: extensive names an unknown parameter")
        if self.state_units and len(self.state_units) != self.states:
            raise VtableError(f"{where}: state_units names {len(self.state_units)} units for "
                              f"{self.states} states")
        if self.states and self.kind not in ("control", "valve", "feedback"):
            raise VtableError(f"{where}: only control, valve and feedback stages have states")

    def values(self, given: dict[str, float]) -> tuple[float, ...]:
        """The named parameters `given` (SI) in declaration order; a missing, unknown or
        non-finite one is an error naming it."""
        unknown = set(given) - set(self.params)
        if unknown:
            raise VtableError(f"stage {self.name!r}: unknown parameter "
                              f"{', '.join(sorted(unknown))}; it takes {', '.join(self.params)}")
        out = []
        for k in self.params:
            if k not in given:
                raise VtableError(f"stage {self.name!r}: parameter {k!r} is missing")
            v = float(given[k])
            if not math.isfinite(v):
                raise VtableError(f"stage {self.name!r}: {k} = {v!r} is not finite")
            out.append(v)
        return tuple(out)

    def source(self) -> str:
        """The laws' source text (a compiled composition is keyed by it)."""
        parts = [self.law] + ([self.rate] if self.rate else [])
        return "\n".join(_source(f) for f in parts)

    def __repr__(self) -> str:
        return f"<{self.kind} stage {self.name}({', '.join(self.params)})>"


def _source(fn: Callable) -> str:
    try:
        text = inspect.getsource(fn)
    except (OSError, TypeError):
        text = fn.__code__.co_code.hex()
    # the module's name too: a compiled law refers to it (a user's file is named by its
    # path, the same in every process)
    return f"{fn.__module__}.{fn.__qualname__}\n{text}\n{_globals_source(fn)}"


def _globals_source(fn: Callable) -> str:
    """The source of module-level functions the law calls (a change in a helper law must
    change the key too)."""
    out = []
    for name in fn.__code__.co_names:
        g = fn.__globals__.get(name)
        target = getattr(g, "py_func", g)
        if inspect.isfunction(target) and target is not fn:
            try:
                out.append(inspect.getsource(target))
            except (OSError, TypeError):
                pass
    return "\n".join(out)


def add_stage(stages: list, stage: Stage, params: dict[str, float]) -> None:
    """Append (stage, params) to an assembly's `stages`, its parameters checked; a stage
    added twice is refused."""
    if not isinstance(stage, Stage):
        raise VtableError(f"add_stage takes a Stage, got {type(stage).__name__}")
    stage.values(params)
    if any(s.name == stage.name for s, _ in stages):
        raise VtableError(f"stage {stage.name!r} is added twice")
    stages.append((stage, {k: float(v) for k, v in params.items()}))
