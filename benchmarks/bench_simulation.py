"""20 s of the §9.2-processed El Centro on the SDOF-frame virtual table (the standard
table's `Physics`, as `vtable.sim.simulate` builds it) with all controllers at a 1 kHz
control rate: wall time, real-time factor, and the ratio to a plain mj_step loop of the
same model and number of steps without controllers, measured in one run (the two timed
alternately, best of 7 each, so a loaded machine slows both alike). Then the whole
`simulate` call (model build, stepping, channels) for the same command."""

from __future__ import annotations

import time

import mujoco

from vtable.params import presets
from vtable.signals import Command, make_command
from vtable.sim import Simulator, simulate, standard_physics
from vtable.sim.run import setup

REPEAT = 7


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main() -> None:
    ph = standard_physics(presets.specimen("sdof_frame"))
    built, ctl, _ = setup(ph, timestep=1e-3)
    full = make_command("earthquake")
    keep = full.t <= 20.0
    cmd = Command(full.name, full.t[keep], full.x[keep], full.table)
    sim = Simulator(built, ctl)
    n_steps = round((cmd.t[-1] - cmd.t[0]) / 1e-3) + 1
    m = built.model
    d = mujoco.MjData(m)

    def controlled() -> None:
        sim.run(cmd.t, {"x": cmd.x}, output_dt=0.005)

    def bare() -> None:
        mujoco.mj_resetData(m, d)
        d.ctrl[len(built.force_actuators)] = built.pit_force
        step = mujoco.mj_step
        for _ in range(n_steps):
            step(m, d)

    controlled()  # the compiled loop loads from numba's cache (or compiles) once
    walls, bares = [], []
    for _ in range(REPEAT):
        walls.append(_timed(controlled))
        bares.append(_timed(bare))
    wall, wall_bare = min(walls), min(bares)
    whole = min(_timed(lambda: simulate(ph, cmd)) for _ in range(3))
    sim_s = n_steps / 1000
    print(f"model: SDOF frame on the EERC table, {m.nq} DOF, {m.nu} actuators, "
          f"{len(sim.state_names)} controller states")
    print(f"steps: {n_steps} at 1 kHz ({sim_s:.1f} s simulated)")
    print(f"with controllers, recording at 200 Hz: {wall:.3f} s wall, "
          f"{sim_s / wall:.0f}x real time")
    print(f"plain mj_step loop:                    {wall_bare:.3f} s wall, "
          f"{sim_s / wall_bare:.0f}x real time")
    print(f"ratio (controllers / bare): {wall / wall_bare:.2f}")
    print(f"whole simulate() (build, step, channels): {whole:.3f} s wall, "
          f"{sim_s / whole:.0f}x real time, {whole / wall_bare:.2f}x the bare loop")


if __name__ == "__main__":
    main()
