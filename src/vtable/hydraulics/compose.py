"""A stage set compiled into the hydraulic element, cached on disk like any module.

`composition(stages, extra)` writes the element for that set of stages (`stage.Stage`) —
`dof_drive`, `fed_back` and `actuator_rates` with each stage's law called in its place,
then the text of the element's group kernels (`element.servo_rates`,
`element.servo_step`) and of `extra` kernels (the reduced model's integrator) — to a real
.py file named by a hash of the stages' laws and the kernels' text, imports it and
returns it. Its kernels are ``njit(cache=True)``: a process that meets the same stage set
again (a diagnosis's workers) loads them compiled from numba's cache instead of
compiling them.

A stage may be *switchable* (`composition(..., switchable=...)`): its law is written in its
place behind a flag in the parameter vector (`Composition.vector`: 1 where the stage is
given, 0 where not, its states' rates then zero), so one compiled module serves every
subset of those stages (the reduced model's nonlinear kernel carries the catalog's stock
stages so: a diagnosis compiles one integrator where it compiled one for each set of
stages it met).

The integrators' loops are compiled without numba's reference counting
(``_nrt=False``, `vtable.models.reduced_kernel._steps`), which no law that allocates an
array can be compiled into: `counted(comp)` is the same element with the counting kept,
and once asked for, `composition` returns it for that stage set in this process.
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import os
import sys
import tempfile
import threading
import types
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np

from vtable.errors import VtableError
from vtable.hydraulics import element
from vtable.hydraulics.element import N_LINEAR, constants_vector
from vtable.hydraulics.stage import KINDS, Stage
from vtable.params.table import ServoConstants

_LAWS: dict[str, list[Callable]] = {}  # key -> the stages' laws, for the generated module
_MODULES: dict[str, Composition] = {}
#: compositions by the identity of the stages and kernels as given (held, so ids stay theirs)
#: and their element laws: hashing the laws' source, even ordering and checking the stages,
#: is slower than the rest of building a reduced model
_SEEN: dict[tuple, tuple[tuple, Composition]] = {}
#: keys of the compositions whose laws need numba's reference counting (`counted`)
_COUNTED: dict[str, Composition] = {}
_UNCOUNTED = ", _nrt=False)"


def laws_of(key: str) -> list[Callable]:
    """The laws of composition `key` (called by its generated module when imported)."""
    return _LAWS[key]


@dataclass(frozen=True)
class Composition:
    """The element of one stage set: its generated `module` (`fed_back`, `actuator_rates`,
    `servo_rates`, `servo_step`, the `extra` kernels), states per actuator `ns`, whether
    every stage is linear, and `key`, which names the module's file (a hash of the stages'
    laws and the kernels' text, then "u": the loops compiled without reference counting,
    or "c": with it, `counted`)."""

    stages: tuple[Stage, ...]
    module: types.ModuleType
    ns: int
    linear: bool
    key: str
    #: how it was made: (stages, templates, elements, switchable), for `counted` to make it
    #: again
    made: tuple = field(compare=False, repr=False)
    #: the names of the stages written behind a flag (`composition`'s `switchable`)
    switchable: frozenset[str] = frozenset()

    def vector(self, h: ServoConstants, values: Sequence[dict[str, float] | None]
               ) -> np.ndarray:
        """The kernel's parameters: `h`'s linear constants, then each stage's named
        parameters (`values`, in the order of `stages`; None: a switchable stage left out,
        its parameters zero), then one flag per switchable stage (1: in, 0: out)."""
        tail, flags = [], []
        for s, p in zip(self.stages, values, strict=True):
            if p is None and s.name not in self.switchable:
                raise VtableError(f"stage {s.name!r} needs its parameters")
            tail += [0.0] * len(s.params) if p is None else s.values(p)
            if s.name in self.switchable:
                flags.append(0.0 if p is None else 1.0)
        return np.concatenate([constants_vector(h), np.asarray(tail + flags, dtype=float)])

    def state_names(self) -> tuple[str, ...]:
        """One actuator's states: P, then each stage's."""
        return ("P", *(f"{s.name}{k}" for s in self.stages for k in range(s.states)))

    def state_units(self) -> tuple[str, ...]:
        """The units of `state_names` (a stage's `state_units`, "1" when it gives none)."""
        return ("Pa", *(u for s in self.stages
                        for u in (s.state_units or ("1",) * s.states)))


def ordered(stages: Sequence[Stage]) -> tuple[Stage, ...]:
    """Stages in the element's order: by kind (valve, flow, pressure, feedback, force),
    then `order`, then name."""
    return tuple(sorted(stages, key=lambda s: (KINDS.index(s.kind), s.order, s.name)))


@dataclass(frozen=True)
class ElementLaw:
    """A force element's law as the generated module calls it: the law (a plain Python
    function f(d, v, z, p, dz) -> force, `vtable.models.reduced.ReducedAssembly.add_force`),
    its states, its parameters' count and their names (None: the law reads an array)."""

    law: Callable
    states: int
    n_params: int
    names: tuple[str, ...] | None = None


def composition(stages: Sequence[Stage], extra: Sequence[Callable] = (),
                elements: Sequence[ElementLaw] = (), switchable: Sequence[Stage] = ()
                ) -> Composition:
    """The compiled element of `stages` (see the module docstring); `extra`: kernels
    (njit-decorated functions of another module) written after the element's, calling its
    `dof_drive`, `fed_back`, `actuator_rates` and its states per actuator `NS`;
    `elements`: force-element laws, called by the module's `elements(q, q̇, z, p, f, ż,
    ia, ib)` on the relative motion of coordinates ia[k] and ib[k] (−1: none), given at run
    time (one compiled module serves every coordinate, every storey); `switchable`: more
    stages, each written behind a flag (the module docstring)."""
    held = (*stages, *switchable, *extra)  # as given: a model built again is looked up
    elements = tuple(elements)  # before its stages are ordered and checked (frozen,
    ident = (tuple(map(id, held)), len(switchable), len(extra), elements)  # by value)
    seen = _SEEN.get(ident)
    if seen is not None and all(a is b for a, b in zip(seen[0], held, strict=True)):
        return _COUNTED.get(seen[1].key, seen[1])
    stages = checked([*stages, *switchable])
    switched = frozenset(s.name for s in switchable)
    templates = [element.servo_rates, element.servo_step, *extra]
    key = _key(stages, templates, elements, switched)
    hit = _MODULES.get(key)
    if hit is not None:
        _SEEN[ident] = (held, hit)
        return _COUNTED.get(key, hit)
    return _compiled(stages, templates, elements, key, held, ident, switched=switched)


def checked(stages: Sequence[Stage]) -> tuple[Stage, ...]:
    """`stages` in the element's order (`ordered`), or a one-line error where they cannot
    make one element (two control or feedback stages, a stage twice); nothing written or
    imported."""
    stages = ordered(stages)
    for kind in ("control", "feedback"):
        if sum(s.kind == kind for s in stages) > 1:
            raise VtableError(f"the element takes one {kind} stage: "
                              f"{', '.join(s.name for s in stages if s.kind == kind)}")
    if len({s.name for s in stages}) < len(stages):
        raise VtableError(f"a stage appears twice: {', '.join(s.name for s in stages)}")
    return stages


def counted(comp: Composition) -> Composition:
    """`comp` with its integrators' loops compiled with numba's reference counting (a law
    that allocates an array needs it; slower), and `composition` returning it from now on
    for that stage set."""
    if comp.key in _COUNTED or not comp.key.endswith("u"):
        return _COUNTED.get(comp.key, comp)
    # (the rule that removes `_UNCOUNTED` lives in this module, whose text names numba's
    # cache folder, the generated files' too: a change to it cannot reuse an old file)
    stages, templates, elements, switched = comp.made
    _COUNTED[comp.key] = _compiled(stages, templates, elements, comp.key[:-1] + "c", None,
                                   None, counting=True, switched=switched)
    return _COUNTED[comp.key]


def _compiled(stages, templates, elements, key: str, held, ident, counting: bool = False,
              switched: frozenset[str] = frozenset()) -> Composition:
    """The module of composition `key` written (once: its file is named by the key) and
    imported."""
    laws: list[Callable] = []
    for s in stages:
        laws += [s.law] + ([s.rate] if s.rate else [])
    laws += [e.law for e in elements]
    _LAWS[key] = laws

    def text() -> str:
        t = _source(stages, templates, key, elements, switched)
        return t.replace(_UNCOUNTED, ")") if counting else t

    module = generated_module(f"vtable_stages_{key}", text)
    comp = Composition(stages, module, 1 + sum(s.states for s in stages),
                       all(s.linear for s in stages), key,
                       (stages, templates, elements, switched), switched)
    if not counting:
        _MODULES[key] = comp
        _SEEN[ident] = (held, comp)
    return comp


def generated_module(name: str, text: Callable[[], str]) -> types.ModuleType:
    """The generated module `name` (its file in `_directory()`, written from `text()` the
    first time: a temporary file per process and thread, then renamed, so that no reader
    meets half a file), imported under that name."""
    path = _directory() / f"{name}.py"
    if not path.exists():
        tmp = path.with_suffix(f".{os.getpid()}.{threading.get_ident()}.tmp")
        tmp.write_text(text())
        # linked, not replaced, should another process have written it meanwhile: numba
        # before 0.68 stamps a source by its time, and a module written again would make
        # what the other compiled stale
        try:
            os.link(tmp, path)
        except FileExistsError:
            pass
        except OSError:  # no hard links here
            os.replace(tmp, path)
        finally:
            tmp.unlink(missing_ok=True)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _key(stages: tuple[Stage, ...], templates: list[Callable],
         elements: tuple[ElementLaw, ...] = (), switched: frozenset[str] = frozenset()
         ) -> str:
    h = hashlib.sha256()
    h.update(f"{numba.__version__} {sys.version}\n".encode())
    if switched:
        h.update(f"switchable {sorted(switched)}\n".encode())
    h.update(inspect.getsource(element).encode())
    for f in templates:
        h.update(inspect.getsource(getattr(f, "py_func", f)).encode())
    for s in stages:
        h.update(f"{s.name} {s.kind} {s.params} {s.states} {s.order}\n".encode())
        h.update(s.source().encode())
        h.update(" ".join(_law_name(f) for f in (s.law, s.rate) if f).encode())
    for e in elements:
        h.update(f"element {e.states} {e.n_params} {e.names} {_law_name(e.law)}\n".encode())
        h.update(_law_source(e.law).encode())
    return h.hexdigest()[:20] + "u"  # "u": the loops uncounted, "c": `counted`


def _law_name(law: Callable) -> str:
    """Where a law lives (module and name): numba's cache of a kernel that calls it names
    its module, so the same source loaded as another module (a user's effects file from
    another folder) is compiled anew, not read back from a cache that cannot find it."""
    law = getattr(law, "py_func", law)
    return f"{law.__module__}.{law.__qualname__}"


def _law_source(law: Callable) -> str:
    """A law's source (its module and name where the source cannot be read)."""
    try:
        return inspect.getsource(getattr(law, "py_func", law))
    except (OSError, TypeError):
        return _law_name(law)


def _directory() -> Path:
    """Where generated modules live: numba's cache directory when one is set, else
    `vtable/hydraulics/__pycache__/stages` (or a temporary directory if that is
    read-only)."""
    base = numba.config.CACHE_DIR
    d = Path(base) / "vtable_stages" if base else Path(__file__).parent / "__pycache__" / "stages"
    try:
        d.mkdir(parents=True, exist_ok=True)
        if not os.access(d, os.W_OK):
            raise OSError(d)
    except OSError:
        d = Path(tempfile.gettempdir()) / f"vtable_stages_{os.getuid()}"
        d.mkdir(parents=True, exist_ok=True)
    return d


def _elements_source(elements: tuple[ElementLaw, ...], first_law: int) -> tuple[list, list]:
    """(module-level lines, the `elements` kernel) calling each element law in turn on the
    relative motion of coordinates ia[k], ib[k] (ib −1: the ground)."""
    head, body = [], ["", "", '@njit(cache=True, inline="always")',
                      "def elements(q, qd, z, p, f, dz, ia, ib):"]
    s = o = 0
    for k, e in enumerate(elements):
        head.append(f"_E{k} = njit(_L[{first_law + k}])")
        args = f"p[{o}:{o + e.n_params}]"
        if e.names is not None:
            head.append(f"_EP{k} = namedtuple('LawParams', {tuple(e.names)!r})")
            args = f"_EP{k}(" + ", ".join(f"p[{o + i}]" for i in range(e.n_params)) + ")"
        body += [f"    i, j = ia[{k}], ib[{k}]",
                 "    d, v = q[i], qd[i]",
                 "    if j >= 0:",
                 "        d -= q[j]",
                 "        v -= qd[j]",
                 f"    r = _E{k}(d, v, z[{s}:{s + e.states}], {args}, dz[{s}:{s + e.states}])",
                 "    f[i] += r",
                 "    if j >= 0:",
                 "        f[j] -= r"]
        s, o = s + e.states, o + e.n_params
    body.append("    return")
    return head, body


def _source(stages: tuple[Stage, ...], templates: list[Callable], key: str,
            elements: tuple[ElementLaw, ...] = (),
            switched: frozenset[str] = frozenset()) -> str:
    names = ", ".join(f"{s.kind} {s.name}" + (" (switchable)" if s.name in switched else "")
                      for s in stages) or "none"
    head = [f'"""Generated by vtable.hydraulics.compose (stages: {names}). Do not edit."""',
            "", "from collections import namedtuple", "", "import numpy as np",
            "from numba import njit", "",
            "from vtable.hydraulics.compose import laws_of",
            "from vtable.hydraulics.element import (bulk_modulus, commanded_flow, dof_error,",
            "                                       oil_column, piston_force)", "",
            f"NS = {1 + sum(s.states for s in stages)}", f'_L = laws_of("{key}")']
    calls: dict[str, list[str]] = {k: [] for k in KINDS}
    rate: list[str] = []
    fed: list[str] = []
    o, so, li = N_LINEAR, 1, 0  # parameter slot, state offset, law index
    flag = N_LINEAR + sum(len(s.params) for s in stages)  # the first switch's slot
    for k, s in enumerate(stages):
        args = ", ".join(f"sp[{o + i}]" for i in range(len(s.params)))
        head.append(f"_P{k} = namedtuple('{s.name}', {tuple(s.params)!r})")
        head.append(f"_law{k} = njit(_L[{li}])")
        p = f"_P{k}({args})"
        z = f"z[o + {so}:o + {so + s.states}]"
        dz = f"dz[o + {so}:o + {so + s.states}]"
        if s.kind == "control":
            line = f"u = _law{k}(u, qc, q, qd, {z}, {p}, {dz})"
        elif s.kind == "valve":
            line = f"q = _law{k}(q, {z}, {p}, {dz})"
        elif s.kind == "flow":
            line = f"q = _law{k}(q, P, {p})"
        elif s.kind == "pressure":
            line = f"beta = _law{k}(beta, P, {p})"
        elif s.kind == "feedback":
            head.append(f"_rate{k} = njit(_L[{li + 1}])")
            line = f"_rate{k}(P, dP, {z}, {p}, {dz})"
        else:
            line = f"F = _law{k}(F, v, {p})"
        if s.name in switched:  # behind its flag; left out, its states' rates are zero
            off = [f"        dz[o + {so + i}] = 0.0" for i in range(s.states)]
            block = [f"    if sp[{flag}] != 0.0:", f"        {line}",
                     *(["    else:", *off] if off else [])]
            if s.kind == "feedback":
                fed += [f"    if sp[{flag}] != 0.0:",
                        f"        return _law{k}(z[o], {z}, {p})"]
            flag += 1
        else:
            block = [f"    {line}"]
            if s.kind == "feedback":
                fed.append(f"    return _law{k}(z[o], {z}, {p})")
        if s.kind == "feedback":
            rate = block
        else:
            calls[s.kind] += block
        o, so, li = o + len(s.params), so + s.states, li + 1 + (s.rate is not None)
    if not any(s.kind == "feedback" and s.name not in switched for s in stages):
        fed.append("    return z[o]")  # no feedback stage, or one switched off
    drive = (["    if not ctl:", "        return dof_error(qc, q, p, qd, g, kp, kv)",
              "    u = dof_error(qc, q, p, qd, 1.0, kp, kv)", *calls["control"],
              "    return g * u"] if calls["control"] else
             ["    return dof_error(qc, q, p, qd, g, kp, kv)"])
    inline = '@njit(cache=True, inline="always")'  # into `reduced_kernel._steps`'s loops
    body = ["", "", inline,
            "def dof_drive(qc, q, p, qd, g, kp, kv, z, o, sp, dz, ctl):",
            *drive, "", "", inline, "def fed_back(z, o, sp):", *fed,
            "", "", inline, "def actuator_rates(z, o, drive, v, sp, dz):",
            "    P = z[o]", "    q = commanded_flow(drive, sp)", *calls["valve"],
            *calls["flow"], "    beta = bulk_modulus(sp)", *calls["pressure"],
            "    dP = oil_column(q, P, v, beta, sp)", "    dz[o] = dP",
            *rate, "    F = piston_force(P, sp)", *calls["force"],
            "    return F", ""]
    eh, eb = _elements_source(elements, li)  # none: `elements` does nothing
    head += eh
    body += eb
    kernels = ["\n" + inspect.getsource(getattr(f, "py_func", f)) for f in templates]
    return "\n".join(head + body) + "\n".join(kernels)
