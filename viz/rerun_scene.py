"""The virtual table in Rerun: the slab pitching in 3D (angles exaggerated), actuators and
stabilizers as lines with force arrows, the specimen, and every channel as a time series,
all logged in bulk with the columnar API, with a blueprint.

This module renders what the simulator computed; it computes nothing physical.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from rerun.chunk import RrdReader
from scipy.spatial.transform import Rotation

from vtable.mjcf.meshes import braced_frame, slab_with_ribs
from vtable.opensees.model import load_model
from vtable.runs.model import FORMAT_UNITS
from vtable.tables.bodies import MASS_BLOCK
from vtable.units import from_si, to_si
from vtable.viz.recording import rrd_file

COLORS = {"horizontal": [50, 100, 230], "vertical": [230, 130, 30], "stabilizer": [80, 180, 80]}
KIP = to_si(1.0, "kip")


def log_run(run, path: str | Path, *, exaggeration: float = 50.0) -> Path:
    """Write an .rrd of a simulated run (`vtable.sim.simulate`'s `SimulatedRun`): its
    simulation's scene and its format channels in their run-file units."""
    named = {k: from_si(v, run.units[k]) for k, v in run.channels.items() if k in FORMAT_UNITS}
    return log_simulation(run.result, path, named, exaggeration=exaggeration)


def log_simulation(res, path: str | Path, channels: dict[str, np.ndarray] | None = None,
                   *, exaggeration: float = 50.0, force_scale: float = 0.02,
                   deformation: float = 10.0, application_id: str = "vtable") -> Path:
    """Write an .rrd of a `SimResult`: scene under ``world/``, channels under
    ``channels/``, each storey's shear against its drift under ``loops/`` (a run with
    storey channels). Pitch and roll are multiplied by `exaggeration` in the 3D view only,
    an OpenSees model's deformation by `deformation`; force arrows are `force_scale` m per
    kip."""
    path = Path(path)
    with rrd_file(path, application_id) as rec:
        _log_simulation(rec, res, channels, exaggeration, force_scale, deformation)
    return path


def storey_loops(rec: rr.RecordingStream, times, channels: dict[str, np.ndarray],
                 prefix: str = "loops") -> list[str]:
    """Each storey's shear against its drift (channels in run-file units): the whole loop as
    a line and the present state as a point moving along it, each axis scaled by its peak
    (a 2D view draws x and y at one scale; y up: the shear is negated for Rerun's
    downward y). Returns the view names' storeys, "storey K: ±D in, ±V kip"."""
    out = []
    k = 1
    while f"floor{k}_drift" in channels and f"floor{k}_shear" in channels:
        d, v = channels[f"floor{k}_drift"], channels[f"floor{k}_shear"]
        dm, vm = float(np.max(np.abs(d))) or 1.0, float(np.max(np.abs(v))) or 1.0
        xy = np.column_stack([d / dm, -v / vm])
        ent = f"{prefix}/storey{k}"
        rec.log(f"{ent}/loop", rr.LineStrips2D([xy], colors=[[60, 110, 180]], radii=[0.004]),
                static=True)
        rr.send_columns(f"{ent}/now", indexes=times, recording=rec,
                        columns=rr.Points2D.columns(positions=xy).partition(
                            np.ones(len(xy), int)))
        rec.log(f"{ent}/now", rr.Points2D.from_fields(colors=[[220, 40, 40]], radii=[0.03]),
                static=True)
        out.append(f"storey {k}: drift ±{dm:.3g} in (right), shear ±{vm:.3g} kip (up)")
        k += 1
    return out


def _log_opensees(rec: rr.RecordingStream, res, times, depth: float, scale: float) -> None:
    """An OpenSees model's elements as lines on the slab, its nodes displaced by `scale`
    times their displacement relative to the platen."""
    model = load_model(res.built.specimen.model)
    nodes = res.specimen.get("nodes") if res.specimen else None
    if nodes is None or not model.elements:
        return
    xy = model.coords[None, :, :] + scale * nodes  # (n_t, n_nodes, 2)
    pos = np.stack([xy[..., 0], np.zeros(xy.shape[:2]), xy[..., 1] + depth], axis=-1)
    ia = [model.index(a) for a, _ in model.elements]
    ib = [model.index(b) for _, b in model.elements]
    strips = np.stack([pos[:, ia], pos[:, ib]], axis=2).reshape(-1, 2, 3)
    ent = "world/table/slab/opensees"
    rr.send_columns(ent, indexes=times, recording=rec,
                    columns=rr.LineStrips3D.columns(strips=strips).partition(
                        np.full(len(xy), len(ia))))
    rec.log(ent, rr.LineStrips3D.from_fields(colors=[[60, 110, 180]], radii=[0.03]),
            static=True)


def _log_simulation(rec: rr.RecordingStream, res, channels, exaggeration: float,
                    force_scale: float, deformation: float = 10.0) -> None:
    b, vt = res.built, res.built.vt
    g, lay = vt.table.geometry, vt.layout
    t = res.t - res.t[0]
    times = [rr.TimeColumn("time", duration=t)]
    n = len(t)
    # static geometry
    slab = slab_with_ribs(g.plan_width, g.thickness, lay.rib_width, lay.rib_depth,
                          lay.rib_offset, vt.pivot_depth)
    rec.log("world/table/slab/mesh", rr.Mesh3D(vertex_positions=slab.vertices,
                                                triangle_indices=slab.faces,
                                                albedo_factor=[180, 180, 175]), static=True)
    rec.log("world/foundation", rr.Boxes3D(centers=[[0, 0, -vt.pivot_depth - 1.0]],
                                           half_sizes=[[4.9, 4.9, 0.05]],
                                           colors=[[120, 110, 100]]), static=True)
    # slab pose, exaggerated in pitch and roll
    q = {j: res.joint(j) for j in ("x", "z", "roll", "pitch", "twist")}
    euler = np.column_stack([exaggeration * q["roll"], exaggeration * q["pitch"], q["twist"]])
    rot = Rotation.from_euler("XYZ", euler)
    origin = np.column_stack([q["x"], np.zeros(n), q["z"] - vt.pivot_depth])
    rr.send_columns("world/table/slab", indexes=times, recording=rec,
                    columns=rr.Transform3D.columns(translation=origin,
                                                   quaternion=rot.as_quat()))
    # specimen
    sb = list(zip(b.structure_joints, b.structure_heights, strict=True))
    if sb:
        if b.specimen.kind == "sdof":
            top = b.structure_heights[-1] - vt.pivot_depth
            fm = braced_frame(to_si(18.0, "ft"), to_si(6.0, "ft"),
                              [to_si(x, "ft") for x in (4.0, 3.0, 3.0)], top - 0.3)
            fm.apply_translation([0, 0, vt.pivot_depth])
            rec.log("world/table/slab/frame", rr.Mesh3D(vertex_positions=fm.vertices,
                                                         triangle_indices=fm.faces,
                                                         albedo_factor=[60, 110, 180]),
                    static=True)
        drift = np.zeros(n)
        for j, h in sb:
            drift = drift + res.joint(j)
            name = "top_mass" if j == "x_s" else j.replace("x_s", "storey")
            ent = f"world/table/slab/{name}"
            rec.log(ent, rr.Boxes3D(half_sizes=[MASS_BLOCK / 2], colors=[[90, 90, 100]]),
                    static=True)
            rr.send_columns(ent, indexes=times, recording=rec,
                            columns=rr.Transform3D.columns(
                                translation=np.column_stack([drift, np.zeros(n),
                                                             np.full(n, h)])))
    elif b.specimen.kind == "opensees":
        _log_opensees(rec, res, times, vt.pivot_depth, deformation)
    elif b.specimen.kind == "rigid":
        rec.log("world/table/slab/specimen", rr.Boxes3D(
            centers=[[0, 0, b.specimen.height]],
            half_sizes=[[b.specimen.size[0] * b.specimen.count / 2, b.specimen.size[2] / 2,
                         b.specimen.size[1] / 2]], colors=[[150, 150, 150]]), static=True)
    # actuators and stabilizers: lines from foundation to slab point, force arrows
    pivot = np.array([0.0, 0.0, -vt.pivot_depth])
    for i, name in enumerate(b.force_actuators):
        a = vt.actuator(name)
        r = np.asarray(a.slab_point) - pivot
        p = origin + rot.apply(r)
        base = np.broadcast_to(a.foundation_point, p.shape)
        strips = np.stack([base, p], axis=1)
        rr.send_columns(f"world/actuators/{name}/line", indexes=times, recording=rec,
                        columns=rr.LineStrips3D.columns(strips=strips).partition(np.ones(n,
                                                                                        int)))
        rec.log(f"world/actuators/{name}/line", rr.LineStrips3D.from_fields(
            colors=[COLORS[a.kind]], radii=[0.03]), static=True)
        axis = (p - base) / np.linalg.norm(p - base, axis=1, keepdims=True)
        vec = axis * (res.forces[:, i] / KIP * force_scale)[:, None]
        rr.send_columns(f"world/actuators/{name}/force", indexes=times, recording=rec,
                        columns=rr.Arrows3D.columns(origins=p, vectors=vec))
        rec.log(f"world/actuators/{name}/force", rr.Arrows3D.from_fields(
            colors=[[220, 40, 40]], radii=[0.02]), static=True)
    # channels
    for name, v in (channels or {}).items():
        rr.send_columns(f"channels/{name}", indexes=times, recording=rec,
                        columns=rr.Scalars.columns(scalars=np.asarray(v, dtype=float)))
    loops = storey_loops(rec, times, channels or {})
    rec.send_blueprint(blueprint(list(channels or {}), loops))


def blueprint(channel_names: list[str], loops: list[str] = ()) -> rrb.Blueprint:
    """3D view beside the table-motion, pitch, pitch-acceleration, force and specimen time
    series (one quantity per view, its unit in its name), and each storey's loop (`loops`:
    `storey_loops`' names) under them."""
    groups = {
        "table motion (in)": ["h_span", "avg_hdisp"],
        "pitch (rad)": ["pitch_disp"],  # one quantity per axis: θ and θ̈ apart
        "pitch acceleration (rad/s²)": ["pitch_acc"],
        "forces (kip)": [c for c in channel_names if c.endswith(("_force", "_stab"))],
        "specimen and commanded acceleration (g)": ["acc_n_ne", "acc_n_nw", "acc_cmd"],
    }
    views = [rrb.TimeSeriesView(name=title, origin="channels",
                                contents=[f"channels/{c}" for c in names if c in channel_names])
             for title, names in groups.items() if any(c in channel_names for c in names)]
    scene = rrb.Spatial3DView(name="virtual table (pitch and roll exaggerated)", origin="world")
    if loops:
        scene = rrb.Vertical(scene, rrb.Horizontal(*[
            rrb.Spatial2DView(name=name, origin=f"loops/storey{k}")
            for k, name in enumerate(loops, 1)]), row_shares=[3, 2])
    return rrb.Blueprint(rrb.Horizontal(
        scene, rrb.Vertical(*views) if views else rrb.TimeSeriesView(origin="channels"),
        column_shares=[3, 2]))


def read_rrd(path: str | Path) -> dict[str, list]:
    """Entity path -> list of (timeline values, component columns) record batches (tests)."""

    out: dict[str, list] = {}
    for ch in RrdReader(str(path)).stream().to_chunks():
        out.setdefault(ch.entity_path, []).append(ch.to_record_batch())
    return out
