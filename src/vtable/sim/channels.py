"""Simulated histories -> the run format's channels (names, units and signs of
docs/run-format.md, report Table 2.3), plus the full state."""

from __future__ import annotations

import mujoco
import numpy as np

from vtable.analytic.structure import storey_channels, storey_masses
from vtable.opensees.model import load_model
from vtable.params.specimen import ShearBuilding
from vtable.runs.model import FORMAT_UNITS, Run
from vtable.sim.simulator import SimResult


def channels(res: SimResult, full_state: bool = True) -> tuple[dict[str, np.ndarray],
                                                              dict[str, str]]:
    """Channel histories in SI, and every channel's unit in a run file (the format's for
    its channels; SI for the extra state channels)."""
    b = res.built
    names = b.force_actuators
    ext = {a: res.extension[:, i] for i, a in enumerate(names)}
    force = {a: res.forces[:, i] for i, a in enumerate(names)}
    # the horizontal force channels as the table measures them (`vt.force_measured`): the
    # force each rod transmits (a load cell), or A·ΔP (the pressure force, eq 6.3)
    delta_p = b.vt.force_measured == "delta_p" and res.pressure_forces is not None
    h_force = ({a: res.pressure_forces[:, i] for i, a in enumerate(names)} if delta_p
               else force)
    hs = [a.name for a in b.vt.group("horizontal")]
    vs = [a.name for a in b.vt.group("vertical")]
    dofs = b.vt.dofs
    si: dict[str, np.ndarray] = {"h_span": res.commands[:, 0],
                                 "avg_hdisp": np.mean([ext[a] for a in hs], axis=0)}
    if vs:
        si["avg_vdisp"] = np.mean([ext[a] for a in vs], axis=0)
    si["avg_hacc"] = res.joint("x", "qacc")
    for name, joint in (("avg_vacc", "z"), ("pitch_acc", "pitch"), ("roll_acc", "roll"),
                        ("twist_acc", "twist")):
        if joint in dofs:
            si[name] = res.joint(joint, "qacc")
    if "pitch" in dofs:
        si["pitch_disp"] = res.joint("pitch")
    # the actuators' velocity transducers, as their displacements (relative to the reaction
    # mass; the platen's own velocity on a rigid foundation)
    vel = {a: res.ext_velocity[:, i] for i, a in enumerate(names)}
    si["h_vel"] = np.mean([vel[a] for a in hs], axis=0)
    si["acc_cmd"] = res.command_acc
    stabs = [a.name for a in b.vt.group("stabilizer")]
    for i, a in enumerate(vs):
        si[f"{a.lower()}_disp"] = ext[a]
        si[f"{a.lower()}_force"] = force[a]
        if i < len(stabs):
            si[f"{stabs[i].lower()}_stab"] = force[stabs[i]]
    for a in hs:
        si[f"{a.lower()}_disp"] = ext[a]
        si[f"{a.lower()}_force"] = h_force[a]
    if b.structure_joints:
        si["acc_n_ne"] = res.sensor("top_ne_acc")[:, 0]
        si["acc_n_nw"] = res.sensor("top_nw_acc")[:, 0]
        if {"roll", "twist"} & set(dofs):  # lateral (west) motion: none on a planar table
            si["acc_w_nw"] = res.sensor("top_nw_acc")[:, 1]
            si["acc_w_sw"] = res.sensor("top_sw_acc")[:, 1]
        for site in ("sw", "se"):
            x = res.sensor(f"top_{site}_pos")[:, 0]
            si[f"pot_n_{site}"] = x - x[0] if len(x) else x
    if isinstance(b.specimen, ShearBuilding):  # every floor, from the bottom
        for k in range(1, len(b.structure_joints) + 1):
            si[f"floor{k}_acc"] = res.sensor(f"floor{k}_acc")[:, 0]
            x = res.sensor(f"floor{k}_pos")[:, 0]
            si[f"floor{k}_disp"] = x - x[0] if len(x) else x
    if res.specimen is not None:  # an OpenSees model's floors (`OpenSeesController.history`)
        si.update(opensees_channels(res))
    if getattr(b.specimen, "hysteresis", None) is not None:  # a yielding specimen's storeys
        n = len(b.structure_joints)
        acc = [si[f"floor{k}_acc"] for k in range(1, n)] + [si["acc_n_ne"]]
        si.update(storey_channels([res.joint(j) for j in b.structure_joints], acc,
                                  storey_masses(b.specimen)))
    out = dict(si)
    extra_units: dict[str, str] = {k: FORMAT_UNITS[k] for k in si}
    if full_state:
        m = b.model
        for j in range(m.njnt):
            jn = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
            slide = m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
            out[f"state_q_{jn}"] = res.qpos[:, m.jnt_qposadr[j]]
            out[f"state_v_{jn}"] = res.qvel[:, m.jnt_dofadr[j]]
            extra_units[f"state_q_{jn}"] = "m" if slide else "rad"
            extra_units[f"state_v_{jn}"] = "m/s" if slide else "rad/s"
        units = res.controller_state_units or ("1",) * len(res.controller_state_names)
        for i, (s, u) in enumerate(zip(res.controller_state_names, units, strict=True)):
            out[f"state_{s}"] = res.controller_states[:, i]
            extra_units[f"state_{s}"] = u  # the stage's (`Stage.state_units`), SI
    return out, extra_units


def opensees_channels(res: SimResult) -> dict[str, np.ndarray]:
    """An OpenSees specimen's floors as a building's (floorK_acc, floorK_disp, floorK_drift,
    floorK_shear, the top floor's instruments) from its recorded relative motion u, ü and
    the platen's: a floor at η above the actuator line moves x_t + θ η + u (small θ)."""
    model = load_model(res.built.specimen.model)
    h = res.specimen
    eta = model.floor_heights + res.built.vt.table.geometry.actuator_line_depth
    x_t, a_t = res.joint("x"), res.joint("x", "qacc")
    theta, alpha = res.joint("pitch"), res.joint("pitch", "qacc")
    out: dict[str, np.ndarray] = {}
    acc, drift = [], []
    for k in range(h["u"].shape[1]):
        a = a_t + alpha * eta[k] + h["a"][:, k]
        x = x_t + theta * eta[k] + h["u"][:, k]
        out[f"floor{k + 1}_acc"] = a
        out[f"floor{k + 1}_disp"] = x - x[0] if len(x) else x
        acc.append(a)
        drift.append(h["u"][:, k] - (h["u"][:, k - 1] if k else 0.0))
    top = h["u"].shape[1]
    out["acc_n_ne"] = out["acc_n_nw"] = out[f"floor{top}_acc"]
    out["pot_n_sw"] = out["pot_n_se"] = out[f"floor{top}_disp"]
    out.update(storey_channels(drift, acc, model.floor_masses))
    return out


def result_run(res: SimResult, meta: dict, name: str, full_state: bool = True,
               step: int = 1) -> Run:
    """A `Run` (SI inside) from a simulation, every `step`-th recorded sample."""
    ch, unit = channels(res, full_state)
    t = res.t[::step] - res.t[0]
    return Run(name=name, time=t, channels={k: v[::step] for k, v in ch.items()}, units=unit,
               meta=meta, extra=[k for k in ch if k not in FORMAT_UNITS])
