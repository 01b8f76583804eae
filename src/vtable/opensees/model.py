"""The user's OpenSees model file, and what vtable reads from the model it builds.

The file defines ``build(ops)``: given ``openseespy.opensees`` (wiped), it builds a planar
model (``ops.model("basic", "-ndm", 2, "-ndf", 3)``: X along the shaking direction from
the table's centre, Y up from the table top), fixes its base node(s) in every DOF, gives
its masses with ``ops.mass`` and may set its damping (``ops.rayleigh``, ...); it returns
``{"base": [...], "floors": [[...], ...], "units": "kip-in"}``: the base node tags, each
floor's node tags from the bottom up (a floor's motion is the mean of its nodes'), and the
units the model is written in (`UNITS`; "N-m" if not given). vtable adds gravity, the
platen's motion and the transient analysis (`vtable.opensees.stepper`).
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vtable.errors import VtableError, did_you_mean
from vtable.opensees.library import explain, opensees
from vtable.userfile import user_module

#: a model's units: (force, length) in N and m; its mass unit is force·s²/length
UNITS = {"N-m": (1.0, 1.0), "kN-m": (1e3, 1.0), "kip-in": (4448.2216152605, 0.0254),
         "lb-in": (4.4482216152605, 0.0254), "kip-ft": (4448.2216152605, 0.3048)}
RETURN_KEYS = ("base", "floors", "units")


@dataclass(frozen=True)
class OpenSeesModel:
    """What vtable knows of a built model, in SI: node tags and coordinates (X from the
    table's centre, Y above the table top), each node's masses per DOF (kg, kg, kg m²),
    the base nodes, each floor's nodes, and the model's units."""

    path: Path
    nodes: tuple[int, ...]
    coords: np.ndarray  # (n, 2), m
    masses: np.ndarray  # (n, 3): m_x, m_y (kg), rotational (kg m²)
    fixed: np.ndarray  # (n, 3) bool: the DOFs the model fixes (ops.fix)
    #: the elements as node-tag pairs (a many-node element: its outline), for drawing
    elements: tuple[tuple[int, int], ...]
    base: tuple[int, ...]
    floors: tuple[tuple[int, ...], ...]
    units: str
    #: the damping build(ops) declared: ("rayleigh", (α_M, β_K, β_Kinit, β_Kcomm)) from
    #: ops.rayleigh, ("modal", (ξ, ...)) from ops.modalDamping, or None (none declared)
    damping: tuple[str, tuple[float, ...]] | None = None

    @property
    def force_unit(self) -> float:
        return UNITS[self.units][0]

    @property
    def length_unit(self) -> float:
        return UNITS[self.units][1]

    @property
    def mass(self) -> float:
        """The total horizontal mass (kg)."""
        return float(self.masses[:, 0].sum())

    def index(self, tag: int) -> int:
        return self.nodes.index(tag)

    @property
    def floor_masses(self) -> np.ndarray:
        """Each floor's horizontal mass (kg): its nodes' m_x."""
        return np.array([sum(self.masses[self.index(t), 0] for t in f) for f in self.floors])

    @property
    def floor_heights(self) -> np.ndarray:
        """Each floor's height above the table top (m): its nodes' mean Y."""
        return np.array([np.mean([self.coords[self.index(t), 1] for t in f])
                         for f in self.floors])

    @property
    def top(self) -> float:
        """The model's highest point above the table top (m)."""
        return float(self.coords[:, 1].max())

    @property
    def welded(self) -> np.ndarray:
        """Each node's mass the platen carries rigidly (kg): a node fixed in a translation
        moves with the platen that way, so its mass is welded to it (the fixed direction's
        mass); 0 for a node free in both translations (`vtable.opensees.stepper`)."""
        fx, fy = self.fixed[:, 0], self.fixed[:, 1]
        return np.where(fy, self.masses[:, 1], np.where(fx, self.masses[:, 0], 0.0))

    @property
    def welded_rotation(self) -> np.ndarray:
        """Each node's rotational mass the platen carries rigidly (kg m²): the nodes whose
        rotation is fixed."""
        return np.where(self.fixed[:, 2], self.masses[:, 2], 0.0)

    def rigid_body(self) -> tuple[float, np.ndarray, float]:
        """(mass kg, centre of mass (X, Y) m, moment of inertia about it in the X-Y plane
        kg m²) of the welded masses (`welded`, `welded_rotation`) as one rigid body."""
        m = self.welded
        total = float(m.sum())
        c = (m[:, None] * self.coords).sum(axis=0) / total if total > 0 else np.zeros(2)
        r2 = ((self.coords - c) ** 2).sum(axis=1)
        return total, c, float((m * r2).sum() + self.welded_rotation.sum())


def load_model(path: str | Path) -> OpenSeesModel:
    """Run the file's ``build(ops)`` and read its model (cached per file and
    modification time). Every problem is one line naming the file."""
    p = Path(path)
    if not p.is_file():
        raise VtableError(f"{p}: no such file ([specimen] model)")
    return _load(p.resolve(), p.stat().st_mtime_ns)


@functools.cache
def _load(p: Path, mtime: int) -> OpenSeesModel:
    del mtime  # part of the cache key only
    ops = opensees()
    out = build(p, ops)
    return read(p, ops, out)


class _Recorder:
    """``openseespy.opensees`` as build(ops) sees it: every call passed on, the damping it
    declares (ops.rayleigh, ops.modalDamping) kept, so that the model's damping can be
    written into a run as data (`vtable.opensees.equivalent`)."""

    def __init__(self, ops) -> None:
        self._ops = ops
        self.damping: tuple[str, tuple[float, ...]] | None = None

    def __getattr__(self, name: str):
        fn = getattr(self._ops, name)
        if name not in ("rayleigh", "modalDamping"):
            return fn

        def kept(*args):
            out = fn(*args)
            try:
                values = tuple(float(a) for a in args)
            except (TypeError, ValueError):
                return out
            self.damping = ("rayleigh" if name == "rayleigh" else "modal", values)
            return out
        return kept


def build(p: Path, ops) -> dict:
    """Run the file's ``build(ops)`` on a wiped OpenSees domain; its returned dict, with
    the damping it declared under the key ``"damping"`` (`_Recorder`)."""
    module = user_module(p, "vtable_opensees_", "[specimen] model")
    fn = getattr(module, "build", None)
    if not callable(fn):
        raise VtableError(f"{p}: defines no build(ops) function (see docs/opensees.md)")
    ops.wipe()
    rec = _Recorder(ops)
    try:
        out = fn(rec)
    except VtableError:
        raise
    except Exception as e:
        raise VtableError(f"{p}: build(ops) raised {type(e).__name__}: {explain(e)}") from None
    if not isinstance(out, dict):
        raise VtableError(f"{p}: build(ops) must return a dict with keys "
                          f"{', '.join(RETURN_KEYS)}, got {type(out).__name__}")
    for k in out:
        if k not in RETURN_KEYS:
            raise VtableError(f"{p}: build(ops) returned unknown key {k!r}"
                              + did_you_mean(k, RETURN_KEYS))
    return {**out, "damping": rec.damping}


def _tags(v, what: str, p: Path) -> tuple[int, ...]:
    if not isinstance(v, list | tuple) or not v or not all(
            isinstance(t, int) and not isinstance(t, bool) for t in v):
        raise VtableError(f"{p}: build(ops) {what}: expected a non-empty list of node tags, "
                          f"got {v!r:.60}")
    return tuple(v)


def read(p: Path, ops, out: dict) -> OpenSeesModel:
    """The built model's nodes, masses, base and floors, checked, in SI."""
    for k in ("base", "floors"):
        if k not in out:
            raise VtableError(f"{p}: build(ops) must return {k!r} (see docs/opensees.md)")
    units = out.get("units", "N-m")
    if units not in UNITS:
        raise VtableError(f"{p}: build(ops) units {units!r}: expected one of "
                          f"{', '.join(UNITS)}" + did_you_mean(str(units), tuple(UNITS)))
    base = _tags(out["base"], "base", p)
    if not isinstance(out["floors"], list | tuple) or not out["floors"]:
        raise VtableError(f"{p}: build(ops) floors: expected a list of floors, each a list of "
                          "node tags, from the bottom up")
    floors = tuple(_tags(f, f"floors[{i}]", p) for i, f in enumerate(out["floors"]))
    nodes = tuple(int(t) for t in ops.getNodeTags())
    ndm = len(ops.nodeCoord(nodes[0])) if nodes else 0
    if ndm != 2 or len(ops.nodeDisp(nodes[0])) != 3:
        raise VtableError(f"{p}: vtable steps planar models (ops.model('basic', '-ndm', 2, "
                          "'-ndf', 3)) in the shaking direction")
    for t in (*base, *(t for f in floors for t in f)):
        if t not in nodes:
            raise VtableError(f"{p}: build(ops) names node {t}, which the model does not have")
    f_u, l_u = UNITS[units]
    coords = np.array([ops.nodeCoord(t) for t in nodes], dtype=float) * l_u
    mass = np.array([(ops.nodeMass(t) + [0.0] * 3)[:3] for t in nodes], dtype=float)
    mass[:, :2] *= f_u / l_u
    mass[:, 2] *= f_u * l_u
    fixed = np.zeros((len(nodes), 3), dtype=bool)
    for t in ops.getFixedNodes():
        for dof in ops.getFixedDOFs(t):
            if 1 <= dof <= 3:
                fixed[nodes.index(int(t)), dof - 1] = True
    for t in base:
        if not fixed[nodes.index(t)].all():
            raise VtableError(f"{p}: base node {t} must be fixed in every DOF "
                              "(ops.fix(node, 1, 1, 1))")
    lines = []
    for e in ops.getEleTags():
        ns = [int(t) for t in ops.eleNodes(e)]
        ring = ns if len(ns) <= 2 else [*ns, ns[0]]
        lines += [(a, b) for a, b in itertools.pairwise(ring) if a != b]
    model = OpenSeesModel(p, nodes, coords, mass, fixed, tuple(lines), base, floors, units,
                          out.get("damping"))
    fm = model.floor_masses
    if np.any(fm <= 0):
        k = int(np.argmax(fm <= 0)) + 1
        raise VtableError(f"{p}: floor {k} has no horizontal mass (give it with ops.mass)")
    if np.any(np.diff(model.floor_heights) <= 0):
        raise VtableError(f"{p}: floors must be listed from the bottom up")
    if np.any(np.abs(coords[[model.index(t) for t in base], 1]) > 1e-6 * max(1.0, model.top)):
        raise VtableError(f"{p}: base nodes must stand on the table top (Y = 0)")
    return model
