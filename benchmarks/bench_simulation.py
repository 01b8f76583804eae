"""20 s of the §9.2-processed El Centro on the SDOF-frame virtual table with all
controllers at a 1 kHz control rate: wall time, real-time factor, and the ratio to a
plain mj_step loop of the same model and number of steps without controllers."""

from __future__ import annotations

import time

import mujoco
import numpy as np

from vtable.mjcf import build
from vtable.params import presets
from vtable.params.virtual import virtual_table
from vtable.sim import Simulator
from vtable.sim.experiment import make_command


def best_of(fn, repeat: int = 5) -> float:
    return min(_timed(fn) for _ in range(repeat))


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main() -> None:
    vt = virtual_table()
    built = build(vt, presets.specimen("sdof_frame"), timestep=1e-3)
    cmd = make_command("earthquake")
    keep = cmd.t <= 20.0
    t, x = cmd.t[keep], cmd.x[keep]
    sim = Simulator(built)
    n_steps = round((t[-1] - t[0]) / 1e-3) + 1
    wall = best_of(lambda: sim.run(t, {"x": x}, output_dt=0.005))
    m = built.model
    d = mujoco.MjData(m)

    def bare() -> None:
        mujoco.mj_resetData(m, d)
        d.ctrl[len(built.force_actuators)] = built.pit_force
        step = mujoco.mj_step
        for _ in range(n_steps):
            step(m, d)

    wall_bare = best_of(bare)
    print(f"model: SDOF frame on the EERC table, {m.nq} DOF, {m.nu} actuators, "
          f"{len(sim.state_names)} controller states")
    print(f"steps: {n_steps} at 1 kHz ({n_steps / 1000:.1f} s simulated)")
    print(f"with controllers, recording at 200 Hz: {wall:.3f} s wall, "
          f"{(n_steps / 1000) / wall:.0f}x real time")
    print(f"plain mj_step loop:                    {wall_bare:.3f} s wall, "
          f"{(n_steps / 1000) / wall_bare:.0f}x real time")
    print(f"ratio (controllers / bare): {wall / wall_bare:.2f}")
    _ = np


if __name__ == "__main__":
    main()
