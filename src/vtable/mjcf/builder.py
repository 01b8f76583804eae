"""The multibody EERC table built with `mujoco.MjSpec` (no XML templates).

World frame: origin at the centre of the table top at rest, x the shaking direction,
z up. The slab body's frame is at the centre of the horizontal actuator line (29.7 in
below the top, §4.2.1), where its joints x, z, roll, pitch and twist act (y is locked as
on the EERC table). Every actuator and stabilizer is a spatial tendon from its foundation
point to its slab point with a force actuator on it, so pitch changes its line of action
and stroke; forces come from the Python controllers. The pit air pressure is a
world-vertical force at the centre of the slab's bottom face balancing the total weight
(§2.2). Specimens hang off the slab: a welded rigid block, a SDOF top mass on a slide
joint with stiffness k_s and damping c_s, or a chain of storeys, each on a slide (its
drift) with the storey's spring, damped by `tables.bodies.specimen_damping` (see
`_add_specimen_damping`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from vtable import units
from vtable.errors import VtableError
from vtable.mjcf import meshes
from vtable.opensees.model import load_model
from vtable.params.specimen import (
    NoSpecimen,
    OpenSeesSpecimen,
    RigidBlock,
    SDOFSpecimen,
    ShearBuilding,
    Specimen,
)
from vtable.params.virtual import VirtualTable
from vtable.tables.bodies import (
    MASS_BLOCK,
    slab_body,
    slab_frame_positions,
    specimen_bodies,
    specimen_damping,
)
from vtable.units import G

SLAB_JOINTS = ("x", "z", "roll", "pitch", "twist")
_J = mujoco.mjtJoint
_NO_COLLIDE = {"contype": 0, "conaffinity": 0}


@dataclass
class BuiltModel:
    """A compiled virtual table and what the simulator needs to know about it."""

    spec: mujoco.MjSpec
    model: mujoco.MjModel
    vt: VirtualTable
    specimen: Specimen
    force_actuators: tuple[str, ...]  # ctrl[0:n] order: H1-H3, V1-V4, P1-P4, then added ones
    structure_joints: tuple[str, ...]
    structure_heights: tuple[float, ...]  # above the actuator line, m
    structure_masses: tuple[float, ...]
    slab_com: np.ndarray  # slab centre of mass in the slab frame (m)
    pit_force: float  # N
    assets: dict[str, bytes] = field(default_factory=dict)

    @property
    def total_weight(self) -> float:
        return self.pit_force


@dataclass
class TableSpec:
    """The virtual table as an `MjSpec` before compilation: bodies, joints, sites and the
    actuators' tendons. Effects edit it (`vtable.mjcf.edit`); `compile_table` then adds
    one force actuator per tendon in `force_actuators` (in that order: the simulator's
    ctrl and sensor order), the pit pressure, the sensors, and compiles."""

    spec: mujoco.MjSpec
    vt: VirtualTable
    specimen: Specimen
    force_actuators: list[str]
    structure_joints: tuple[str, ...]
    structure_heights: tuple[float, ...]
    structure_masses: tuple[float, ...]
    slab_com: np.ndarray
    weight: float  # N, balanced by the pit pressure
    assets: dict[str, bytes]
    top_body: str | None  # where the top-mass instruments are


def build(vt: VirtualTable, specimen: Specimen | None = None, *, timestep: float = 1e-3,
          with_meshes: bool = True) -> BuiltModel:
    """Build and compile the virtual table carrying `specimen` (bare table by default)."""
    return compile_table(table_spec(vt, specimen, timestep=timestep, with_meshes=with_meshes))


def table_spec(vt: VirtualTable, specimen: Specimen | None = None, *, timestep: float = 1e-3,
               with_meshes: bool = True) -> TableSpec:
    """The virtual table's `MjSpec`, ready for edits (see `TableSpec`)."""
    specimen = specimen or NoSpecimen()
    check_specimen(vt, specimen)
    s = mujoco.MjSpec()
    s.modelname = f"{vt.name}_virtual_table" + ("" if isinstance(specimen, NoSpecimen)
                                                else f"_{specimen.kind}")
    s.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    s.compiler.autolimits = True
    s.option.timestep = timestep
    s.option.gravity = [0.0, 0.0, -G]
    s.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    s.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    s.visual.global_.offwidth, s.visual.global_.offheight = 960, 720
    g, lay = vt.table.geometry, vt.layout
    pivot = g.actuator_line_depth
    assets: dict[str, bytes] = {}

    def add_mesh(name: str, mesh) -> str:
        fname = f"{name}.stl"
        assets[fname] = meshes.to_stl(mesh)
        s.add_mesh(name=name, file=fname)
        return name

    world = s.worldbody
    world.add_site(name="world_ref")
    world.add_light(name="sun", pos=[0, -10, 12], dir=[0, 0.6, -1])
    world.add_camera(name="side", pos=[0.0, -16.0, 3.0], xyaxes=[1, 0, 0, 0, 0.2, 1])
    slab = world.add_body(name="slab", pos=[0, 0, -pivot])
    sb = slab_body(vt)
    com = np.array(sb.com)
    slab.explicitinertial = True
    slab.mass, slab.ipos, slab.inertia = sb.mass, com, sb.inertia
    for name in SLAB_JOINTS:
        if name in vt.dofs:
            j = slab.add_joint(name=name, **JOINT_KIND[name])
            if name == "x" and vt.horizontal_servo.damping:  # the platen's viscous damping
                j.damping[0] = vt.horizontal_servo.damping * len(vt.group("horizontal"))
    if with_meshes:
        mesh = add_mesh("slab", meshes.slab_with_ribs(g.plan_width, g.thickness, lay.rib_width,
                                                      lay.rib_depth, lay.rib_offset, pivot))
        slab.add_geom(name="slab", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh,
                      rgba=[0.7, 0.7, 0.68, 1], **_NO_COLLIDE)
    else:
        slab.add_geom(name="slab", type=mujoco.mjtGeom.mjGEOM_BOX,
                      size=[g.plan_width / 2, g.plan_width / 2, g.thickness / 2],
                      pos=[0, 0, pivot - g.thickness / 2], **_NO_COLLIDE)
    slab.add_site(name="pit", pos=[0, 0, pivot - g.thickness])
    names = []
    for a in vt.actuators:
        sp = np.subtract(a.slab_point, [0, 0, -pivot])
        slab.add_site(name=f"{a.name}_slab", pos=sp, size=[0.04, 0, 0])
        world.add_site(name=f"{a.name}_base", pos=a.foundation_point, size=[0.04, 0, 0])
        t = s.add_tendon(name=a.name)
        t.wrap_site(f"{a.name}_base")
        t.wrap_site(f"{a.name}_slab")
        t.rgba = {"horizontal": [0.2, 0.4, 0.9, 1], "vertical": [0.9, 0.5, 0.1, 1],
                  "stabilizer": [0.3, 0.7, 0.3, 1]}[a.kind]
        t.width = 0.05 if a.kind == "horizontal" else 0.04
        names.append(a.name)
    joints, heights, masses = _add_specimen(s, slab, specimen, pivot, with_meshes, add_mesh)
    rigid = (specimen.mass if isinstance(specimen, RigidBlock) else load_model(specimen.model).mass
             if isinstance(specimen, OpenSeesSpecimen) else 0.0)
    weight = (g.mass + sum(masses) + rigid) * G
    top = None
    if joints:
        top = "top_mass" if joints[-1] == "x_s" else joints[-1].replace("x_s", "storey")
    return TableSpec(s, vt, specimen, names, tuple(joints), tuple(heights), tuple(masses), com,
                     weight, assets, top)


#: the slab's joints at the horizontal actuator line (y is locked as on the EERC table)
JOINT_KIND = {"x": {"type": _J.mjJNT_SLIDE, "axis": [1, 0, 0]},
              "z": {"type": _J.mjJNT_SLIDE, "axis": [0, 0, 1]},
              "roll": {"type": _J.mjJNT_HINGE, "axis": [1, 0, 0]},
              "pitch": {"type": _J.mjJNT_HINGE, "axis": [0, 1, 0]},
              "twist": {"type": _J.mjJNT_HINGE, "axis": [0, 0, 1]}}


def compile_table(ts: TableSpec) -> BuiltModel:
    """Add the force actuators (one per tendon of `ts.force_actuators`, in order), the pit
    pressure after them, the sensors (every force actuator's length, then velocity, then
    the top-mass instruments, then a shear building's floors), and compile."""
    s = ts.spec.copy()
    s.assets = dict(ts.assets)
    for a in ts.force_actuators:
        s.add_actuator(name=a, target=a, trntype=mujoco.mjtTrn.mjTRN_TENDON)
    pit = s.add_actuator(name="pit_pressure", target="pit", trntype=mujoco.mjtTrn.mjTRN_SITE,
                         refsite="world_ref")
    pit.gear = [0, 0, 1, 0, 0, 0]
    for a in ts.force_actuators:
        s.add_sensor(name=f"{a}_len", type=mujoco.mjtSensor.mjSENS_TENDONPOS, objname=a,
                     objtype=mujoco.mjtObj.mjOBJ_TENDON)
    for a in ts.force_actuators:
        s.add_sensor(name=f"{a}_vel", type=mujoco.mjtSensor.mjSENS_TENDONVEL, objname=a,
                     objtype=mujoco.mjtObj.mjOBJ_TENDON)
    if ts.top_body:  # accelerometers and potentiometers on the top mass (Table 2.3)
        b = ts.top_body
        for site in ("ne", "nw", "sw"):
            s.add_sensor(name=f"top_{site}_acc", type=mujoco.mjtSensor.mjSENS_FRAMELINACC,
                         objname=f"{b}_{site}", objtype=mujoco.mjtObj.mjOBJ_SITE)
        for site in ("sw", "se"):
            s.add_sensor(name=f"top_{site}_pos", type=mujoco.mjtSensor.mjSENS_FRAMEPOS,
                         objname=f"{b}_{site}", objtype=mujoco.mjtObj.mjOBJ_SITE)
    if isinstance(ts.specimen, ShearBuilding):  # each floor's frame (format floorK_acc/_disp)
        for k, jn in enumerate(ts.structure_joints, 1):
            for what, kind in (("acc", mujoco.mjtSensor.mjSENS_FRAMELINACC),
                               ("pos", mujoco.mjtSensor.mjSENS_FRAMEPOS)):
                s.add_sensor(name=f"floor{k}_{what}", type=kind,
                             objname=jn.replace("x_s", "storey"),
                             objtype=mujoco.mjtObj.mjOBJ_BODY)
    try:
        model = s.compile()
    except ValueError as e:
        raise VtableError(f"MuJoCo could not compile the virtual table: {e}") from None
    return BuiltModel(spec=s, model=model, vt=ts.vt, specimen=ts.specimen,
                      force_actuators=tuple(ts.force_actuators),
                      structure_joints=ts.structure_joints,
                      structure_heights=ts.structure_heights,
                      structure_masses=ts.structure_masses, slab_com=ts.slab_com,
                      pit_force=ts.weight, assets=dict(ts.assets))


def _add_specimen(s, slab, spec: Specimen, pivot: float, with_meshes: bool, add_mesh):
    """Bodies from `specimen_bodies` (the same list the analytic model reads); an OpenSees
    model's masses as one rigid body (`_add_opensees_body`)."""
    if isinstance(spec, OpenSeesSpecimen):
        _add_opensees_body(slab, spec, pivot)
        return [], [], []
    bodies = specimen_bodies(spec)
    made = {"slab": slab}
    joints, heights, masses = [], [], []
    pos = slab_frame_positions(bodies)
    for b in bodies:
        body = made[b.parent].add_body(name=b.name, pos=b.pos)
        body.explicitinertial = True
        body.mass, body.ipos, body.inertia = b.mass, b.com, b.inertia
        made[b.name] = body
        if b.name == "specimen":
            ext, n = np.array(b.size[:3]), int(b.size[3])
            for i in range(n):
                x = (i - (n - 1) / 2) * ext[0]
                body.add_geom(name=f"block{i + 1}", type=mujoco.mjtGeom.mjGEOM_BOX,
                              size=[ext[0] / 2 * 0.98, ext[2] / 2, ext[1] / 2], pos=[x, 0, 0],
                              rgba=[0.6, 0.6, 0.6, 1], **_NO_COLLIDE)
            continue
        jnt = body.add_joint(name=b.joint, type=_J.mjJNT_SLIDE, axis=[1, 0, 0])
        jnt.stiffness[0] = b.stiffness
        joints.append(b.joint)
        heights.append(float(pos[b.name][2]))
        masses.append(b.mass)
        body.add_geom(name=f"{b.name}_mass", type=mujoco.mjtGeom.mjGEOM_BOX,
                      size=MASS_BLOCK / 2, rgba=[0.35, 0.35, 0.4, 1], **_NO_COLLIDE)
        # instruments at the top beams' corners (Fig 2.5); y = z × x points west
        cx, cy = MASS_BLOCK[0] / 2, MASS_BLOCK[1] / 2
        for site, x, y in (("ne", cx, -cy), ("nw", cx, cy), ("sw", -cx, cy), ("se", -cx, -cy)):
            body.add_site(name=f"{b.name}_{site}", pos=[x, y, 0])
    if isinstance(spec, SDOFSpecimen) and with_meshes:
        top_above = spec.height - pivot  # top mass above the table top
        heights_ft = [4.0, 3.0, 3.0]  # §2.4: first floor 4 ft, then 3 ft storeys
        fm = meshes.braced_frame(units.to_si(18.0, "ft"), units.to_si(6.0, "ft"),
                                 [units.to_si(x, "ft") for x in heights_ft], top_above - 0.3)
        mesh = add_mesh("braced_frame", fm)
        slab.add_geom(name="braced_frame", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=mesh,
                      pos=[0, 0, pivot], rgba=[0.25, 0.45, 0.7, 1], **_NO_COLLIDE)
    _add_specimen_damping(s, spec, joints)
    return joints, heights, masses


def _add_opensees_body(slab, spec: OpenSeesSpecimen, pivot: float) -> None:
    """The OpenSees model's masses, welded to the slab as one rigid body (its mass, centre
    and inertia: `OpenSeesModel.rigid_body`); the model itself adds only what its relative
    motion changes (`vtable.opensees.stepper`). Inertia about x and z from the masses'
    spread (the model is planar: none across it), the nodes' rotational masses added to
    all three axes."""
    built = load_model(spec.model)
    mass, c, _ = built.rigid_body()
    if mass <= 0:
        return
    r = built.coords - c
    m = built.masses[:, 0]
    rot = float(built.masses[:, 2].sum())
    i_x, i_z = float((m * r[:, 1] ** 2).sum()), float((m * r[:, 0] ** 2).sum())
    floor = 1e-6 * mass  # a stick model has no spread across one axis
    body = slab.add_body(name="specimen", pos=[c[0], 0.0, c[1] + pivot])
    body.explicitinertial = True
    body.mass, body.ipos = mass, [0.0, 0.0, 0.0]
    body.inertia = [i_x + rot + floor, i_x + i_z + rot + floor, i_z + rot + floor]


#: prefix of the fixed tendons that carry a building's damping (`_add_specimen_damping`)
DAMPING_TENDON = "storey_damping"


def _add_specimen_damping(s, spec: Specimen, joints: list[str]) -> None:
    """Realise the specimen's slide damping matrix C_d (`tables.bodies.specimen_damping`)
    with MuJoCo's passive elements.

    A single slide (SDOF frame): joint damping c_s. Several (a shear building, whose modal
    damping couples the storeys): C_d is symmetric positive semi-definite, so
    C_d = Σ_k λ_k v_k v_kᵀ (λ_k ≥ 0); fixed tendon k has length v_kᵀ d over the storey
    drifts d and damping λ_k, and its passive force -λ_k v_kᵀ ḋ acts on the joints through
    the tendon Jacobian v_k: -λ_k v_k v_kᵀ ḋ, the rank-one term. MuJoCo's Euler integrator
    takes joint damping implicitly but tendon damping explicitly; the explicit step is
    stable while h·2ξ_nω_n (ω_n the building's highest mode, ξ_n its own ratio: per mode,
    or Rayleigh's α/(2ω_n) + βω_n/2, which grows with ω_n) is well below 2 (2e-2 for
    ξ_n = 5 % and a 30 Hz top mode at the 1 kHz step).
    """
    C_d = specimen_damping(spec)
    if len(joints) != C_d.shape[0]:
        raise VtableError(f"specimen damping has {C_d.shape[0]} slides, the model "
                          f"{len(joints)}")  # two lists of the same bodies: cannot happen
    if len(joints) == 1:
        s.joint(joints[0]).damping[0] = float(C_d[0, 0])
        return
    lam, V = np.linalg.eigh(C_d)
    for k, (lk, vk) in enumerate(zip(lam, V.T, strict=True), 1):
        if lk <= 0.0:  # a null direction (ξ = 0), or rounding below zero of one
            continue
        t = s.add_tendon(name=f"{DAMPING_TENDON}{k}")
        for jn, coef in zip(joints, vk, strict=True):
            t.wrap_joint(jn, float(coef))
        t.damping[0] = float(lk)


def check_specimen(vt: VirtualTable, spec: Specimen) -> None:
    """Table 2.2 limits: weight capacity (130 kips) and overhead clearance (40 ft; none on
    a table that declares none)."""
    specs = vt.table.specs
    top_clear = specs.overhead_clearance
    line = vt.table.geometry.actuator_line_depth
    if isinstance(spec, NoSpecimen):
        return
    weight = (load_model(spec.model).mass if isinstance(spec, OpenSeesSpecimen) else
              spec.mass) * G
    if specs.weight_capacity is not None and weight > specs.weight_capacity:
        raise VtableError(f"specimen weighs {units.from_si(weight, 'kip'):.1f} kips, above the "
                          f"table's capacity of {units.from_si(specs.weight_capacity, 'kip'):g} "
                          f"kips ({vt.limits_source})")
    tops = {RigidBlock: lambda: spec.height + (spec.size[1] / 2 if spec.size else 0.0),
            SDOFSpecimen: lambda: spec.height,
            ShearBuilding: lambda: max(spec.heights),
            OpenSeesSpecimen: lambda: load_model(spec.model).top + line}
    top = tops[type(spec)]() - line
    if top_clear is not None and top > top_clear:
        raise VtableError(f"specimen reaches {units.from_si(top, 'ft'):.1f} ft above the table "
                          f"top, above the {units.from_si(top_clear, 'ft'):g} ft overhead "
                          f"clearance ({vt.limits_source})")
