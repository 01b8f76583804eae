"""Runs of the virtual table (MuJoCo + controllers) built from a `Physics`: the data the
diagnosis is proven on. Every effect present is switched on in the multibody model with
the same parameters the reduced model reads."""

from __future__ import annotations

from vtable.controllers import PassiveStabilizers, ServoController
from vtable.controllers.effect_servo import KernelServo, QuadraticDamper
from vtable.effects import physics as phys
from vtable.effects.catalog import SERVO_EFFECTS
from vtable.effects.sensor import sensor_filter
from vtable.mjcf import build
from vtable.params.virtual import VirtualTable, virtual_table, with_rocking
from vtable.runs import specimen_table
from vtable.runs.model import Run, with_noise
from vtable.sim.channels import result_run
from vtable.sim.experiment import Command
from vtable.sim.simulator import Simulator

OUTPUT_DT = 0.005


def virtual_setup(ph: phys.Physics, vt: VirtualTable | None = None):
    """The built model and controllers that realise `ph` on the virtual table."""
    vt = vt or virtual_table()
    vt = vt.__class__(**{**vt.__dict__, "horizontal_servo": phys.servo_constants(ph, vt)})
    if ph.has("pitch_flexibility"):
        vt = with_rocking(vt, *phys.rocking_spring(ph))
    locked = () if ph.has("pitch_flexibility") else ("pitch",)
    fnd = phys.foundation(ph, vt) if ph.has("foundation_compliance") else None
    c2 = phys.quadratic_damping(ph, ph.specimen)
    built = build(vt, ph.specimen, locked=locked, foundation=fnd,
                  structure_actuators=c2 > 0, with_meshes=False)
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
                name: str = "", vt: VirtualTable | None = None) -> Run:
    """Simulate `command` on the virtual table realising `ph`; channels at 200 Hz through
    the sensor filter when present, plus `noise` x RMS white sensor noise."""
    built, ctl = virtual_setup(ph, vt)
    res = Simulator(built, ctl).run(command.t, {"x": command.x}, output_dt=0.001)
    meta = {"title": name or f"{command.name} ({ph.label})", "table": {"preset": "eerc"},
            "specimen": specimen_table(ph.specimen), "command": command.table}
    run = result_run(res, meta, name or command.name, full_state=False)
    if ph.has("sensor_filter"):
        fc = ph.effects["sensor_filter"]["cutoff_hz"]
        run.channels = {k: (v if k in ("h_span", "acc_cmd") else sensor_filter(v, 1000.0, fc))
                        for k, v in run.channels.items()}
    step = round(OUTPUT_DT / 0.001)
    run.time = run.time[::step]
    run.channels = {k: v[::step] for k, v in run.channels.items()}
    run.reports.append(f"virtual table: {ph.label}")
    return with_noise(run, noise, seed) if noise else run
