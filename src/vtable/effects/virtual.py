"""Runs of the virtual table (MuJoCo + controllers) built from a `Physics`: the data the
diagnosis is proven on. Every effect present is switched on in the multibody model with
the same parameters the reduced model reads."""

from __future__ import annotations

import math

import numpy as np

from vtable.controllers import PassiveStabilizers, ServoController
from vtable.controllers.effect_servo import KernelServo, QuadraticDamper
from vtable.effects import physics as phys
from vtable.effects.catalog import SERVO_EFFECTS
from vtable.effects.sensor import sensor_filter
from vtable.errors import VtableError
from vtable.mjcf import build
from vtable.params.virtual import VirtualTable, virtual_table, with_rocking
from vtable.runs import specimen_table
from vtable.runs.model import Run, with_noise
from vtable.sim.channels import result_run
from vtable.sim.experiment import Command
from vtable.sim.simulator import Simulator

OUTPUT_FS = 200.0  # Hz: the rate of the runs the diagnosis tests are made of
MAX_STEP = 1e-3  # s: the virtual table's largest MuJoCo/control step


def virtual_setup(ph: phys.Physics, vt: VirtualTable | None = None, timestep: float = MAX_STEP):
    """The built model and controllers that realise `ph` on the virtual table (MuJoCo and
    control step `timestep`)."""
    vt = vt or virtual_table()
    vt = vt.__class__(**{**vt.__dict__, "horizontal_servo": phys.servo_constants(ph, vt)})
    if ph.has("pitch_flexibility"):
        vt = with_rocking(vt, *phys.rocking_spring(ph))
    locked = () if ph.has("pitch_flexibility") else ("pitch",)
    fnd = phys.foundation(ph, vt) if ph.has("foundation_compliance") else None
    c2 = phys.quadratic_damping(ph, ph.specimen)
    built = build(vt, ph.specimen, locked=locked, foundation=fnd,
                  structure_actuators=c2 > 0, with_meshes=False, timestep=timestep)
    if any(ph.has(e) for e in SERVO_EFFECTS):
        ctl = [KernelServo(vt, phys.servo_vector(ph, vt, 1)),
               ServoController(vt, rc_filter=(), groups=("vertical",))]
    else:
        ctl = [ServoController(vt, rc_filter=())]
    ctl.append(PassiveStabilizers(vt))
    if c2 > 0:
        ctl.append(QuadraticDamper(c2, tuple(a for a in built.force_actuators
                                             if a.startswith("S"))))
    return built, ctl


def virtual_run(ph: phys.Physics, command: Command, *, noise: float = 0.0, seed: int = 0,
                name: str = "", vt: VirtualTable | None = None,
                output_fs: float = OUTPUT_FS) -> Run:
    """Simulate `command` on the virtual table realising `ph`; channels sampled at
    `output_fs` (Hz, 200 by default) through the sensor filter when present, plus `noise` x
    RMS white sensor noise.

    The table is simulated at the step 1/(k·output_fs), k = ⌈1 kHz/output_fs⌉ (1 ms at 200 Hz
    and 1 kHz, 1/1024 s at 256 Hz), and every k-th sample is kept (the analog sensor filter,
    when present, is applied at the simulation rate before that sampling)."""
    if not output_fs > 0:
        raise VtableError(f"output rate {output_fs:g} Hz: expected a positive rate")
    k = max(1, math.ceil(1.0 / (MAX_STEP * output_fs) - 1e-9))
    dt = 1.0 / (k * output_fs)
    built, ctl = virtual_setup(ph, vt, timestep=dt)
    res = Simulator(built, ctl).run(command.t, {"x": command.x}, output_dt=dt)
    meta = {"title": name or f"{command.name} ({ph.label})", "table": {"preset": "eerc"},
            "specimen": specimen_table(ph.specimen), "command": command.table}
    run = result_run(res, meta, name or command.name, full_state=False)
    if ph.has("sensor_filter"):
        fc = ph.effects["sensor_filter"]["cutoff_hz"]
        run.channels = {c: (v if c in ("h_span", "acc_cmd") else sensor_filter(v, 1.0 / dt, fc))
                        for c, v in run.channels.items()}
    run.time = np.arange(len(run.time[::k])) / output_fs
    run.channels = {c: v[::k] for c, v in run.channels.items()}
    run.reports.append(f"virtual table: {ph.label}, sampled at {output_fs:g} Hz")
    return with_noise(run, noise, seed) if noise else run
