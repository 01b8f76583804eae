"""Edits of the virtual table's `MjSpec` before compilation (MuJoCo's own spec editing):
what effects do to the multibody table instead of flags threaded into `build`.

Each function edits a `TableSpec` in place; `compile_table` then adds the actuators and
sensors of every tendon listed in `TableSpec.force_actuators`.
"""

from __future__ import annotations

import mujoco
import numpy as np

from vtable.errors import VtableError
from vtable.mjcf.builder import JOINT_KIND, SLAB_JOINTS, TableSpec

_J = mujoco.mjtJoint
_NO_COLLIDE = {"contype": 0, "conaffinity": 0}


def _has_joint(ts: TableSpec, name: str) -> bool:
    return any(j.name == name for j in ts.spec.joints)


def lock_joint(ts: TableSpec, name: str) -> None:
    """Remove a slab joint: the platen no longer moves in that DOF."""
    if name not in SLAB_JOINTS:
        raise VtableError(f"cannot lock {name!r}; slab joints are {', '.join(SLAB_JOINTS)}")
    if _has_joint(ts, name):
        ts.spec.delete(ts.spec.joint(name))


def unlock_joint(ts: TableSpec, name: str) -> None:
    """Give the slab back a joint that `lock_joint` removed (no-op when it has it)."""
    if name not in SLAB_JOINTS:
        raise VtableError(f"cannot unlock {name!r}; slab joints are {', '.join(SLAB_JOINTS)}")
    if not _has_joint(ts, name):
        ts.spec.body("slab").add_joint(name=name, **JOINT_KIND[name])


def _move_site(ts: TableSpec, site: str, body) -> None:
    """Re-attach a site to `body` at the same world position (the bodies' frames are
    world-aligned at rest)."""
    old = ts.spec.site(site)
    pos = np.array(old.pos, dtype=float)
    parent = old.parent
    world = np.array(parent.pos, dtype=float) + pos if parent.name != "world" else pos
    size = list(old.size)
    ts.spec.delete(old)
    body.add_site(name=site, pos=world - np.array(body.pos, dtype=float), size=size)


def add_reaction_mass(ts: TableSpec, name: str, mass: float, stiffness: float,
                      damping: float) -> None:
    """The horizontal actuators' bases on a body of `mass` sliding in x on a spring and
    dashpot to the ground (a compliant reaction mass and foundation)."""
    _new_body(ts, name)
    body = ts.spec.worldbody.add_body(name=name)
    body.explicitinertial = True
    body.mass, body.inertia = mass, [mass, mass, mass]
    j = body.add_joint(name=f"{name}_x", type=_J.mjJNT_SLIDE, axis=[1, 0, 0])
    j.stiffness[0], j.damping[0] = stiffness, damping
    for a in ts.vt.group("horizontal"):
        _move_site(ts, f"{a.name}_base", body)


def insert_at_actuators(ts: TableSpec, name: str, mass: float) -> list[str]:
    """A body of mass/n between each horizontal actuator and the platen (a piston on a
    slide in x, where the actuator now ends); returns the new tendons, one per actuator,
    whose length is the piston's travel relative to the platen's attachment point
    (x_piston - x + y·ψ: slide, slab x and twist), for a force law to act on."""
    acts = ts.vt.group("horizontal")
    out = []
    for a in acts:
        body = ts.spec.worldbody.add_body(name=f"{name}_{a.name}", pos=list(a.slab_point))
        body.explicitinertial = True
        m = mass / len(acts)
        body.mass, body.inertia = m, [m, m, m]
        body.add_joint(name=f"{name}_{a.name}_x", type=_J.mjJNT_SLIDE, axis=[1, 0, 0])
        _move_site(ts, f"{a.name}_slab", body)
        t = ts.spec.add_tendon(name=f"{name}_{a.name}_gap")
        t.wrap_joint(f"{name}_{a.name}_x", 1.0)
        t.wrap_joint("x", -1.0)
        if _has_joint(ts, "twist"):
            t.wrap_joint("twist", float(a.slab_point[1]))
        out.append(t.name)
    ts.force_actuators.extend(out)
    return out


def add_storey_actuators(ts: TableSpec, prefix: str = "S") -> list[str]:
    """A tendon on each storey's slide (its length is the storey drift) for a force law to
    act on; returns their names (S1, S2, ...); existing ones are returned again."""
    names = [f"{prefix}{j}" for j in range(1, len(ts.structure_joints) + 1)]
    for jn, tn in zip(ts.structure_joints, names, strict=True):
        if tn not in ts.force_actuators:
            t = ts.spec.add_tendon(name=tn)
            t.wrap_joint(jn, 1.0)
            ts.force_actuators.append(tn)
    return names


def add_slide_body(ts: TableSpec, name: str, mass: float) -> None:
    """A body of `mass` sliding in x on a joint named `name` (a new coordinate), tied to
    nothing until a spring, a force or the actuators are."""
    _new_body(ts, name)
    body = ts.spec.worldbody.add_body(name=name)
    body.explicitinertial = True
    body.mass, body.inertia = mass, [mass, mass, mass]
    body.add_joint(name=name, type=_J.mjJNT_SLIDE, axis=[1, 0, 0])


def _new_body(ts: TableSpec, name: str) -> None:
    """Refuse a second body of one name (two effects adding the same part)."""
    if ts.spec.body(name) is not None:
        raise VtableError(f"the virtual table already has a body named {name!r}: two effects "
                          "add the same part")


def _joint(ts: TableSpec, name: str):
    if not _has_joint(ts, name):
        raise VtableError(f"the virtual table has no coordinate {name!r} (its joints: "
                          f"{', '.join(j.name for j in ts.spec.joints)})")
    return ts.spec.joint(name)


def relative_tendon(ts: TableSpec, name: str, a: str, b: str | None) -> str:
    """A tendon whose length is q_a - q_b (b None: q_a) of two joints."""
    _joint(ts, a)
    t = ts.spec.add_tendon(name=name)
    t.wrap_joint(a, 1.0)
    if b is not None:
        _joint(ts, b)
        t.wrap_joint(b, -1.0)
    return t.name


def add_spring(ts: TableSpec, a: str, b: str | None, stiffness: float,
               damping: float) -> None:
    """A spring and dashpot on joint a (to the ground) or between joints a and b (a
    tendon's spring, its rest length that at rest)."""
    if b is None:
        j = _joint(ts, a)
        j.stiffness[0] += stiffness
        j.damping[0] += damping
        return
    t = ts.spec.tendon(relative_tendon(ts, f"spring_{a}_{b}_{len(ts.spec.tendons)}", a, b))
    t.stiffness[0], t.damping[0] = stiffness, damping


def set_actuator(ts: TableSpec, moving: str | None = None, reaction: str | None = None) -> None:
    """The horizontal actuators end on the body of joint `moving` and/or start on the body
    of joint `reaction` (instead of the platen and the ground)."""
    for joint, end in ((moving, "slab"), (reaction, "base")):
        if joint is not None:
            body = _joint(ts, joint).parent
            for act in ts.vt.group("horizontal"):
                _move_site(ts, f"{act.name}_{end}", body)
