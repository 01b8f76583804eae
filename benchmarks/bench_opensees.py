"""Speed of an OpenSees specimen on the virtual table (issue 21's figure: a nonlinear
3-storey fibre frame steps at >= 1x real time at the control rate): the README's frame
(examples/opensees_frame.py: 6 fibre columns, Steel02, 4 Lobatto points, PDelta) under
El Centro at 3 in on the EERC table at the 1 kHz control step. Printed: the per-step cost
of the model alone (OpenSees' Newton step and vtable's loads and reads), of the whole
co-simulated step, and the real-time factor; the same table carrying vtable's own shear
building for reference.

    python benchmarks/bench_opensees.py"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from vtable.opensees.equivalent import equivalent_building
from vtable.opensees.stepper import OpenSeesStepper
from vtable.signals.command import make_command
from vtable.sim.experiment import load_specimen, run_experiment
from vtable.tables.eerc import virtual_table

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def main() -> None:
    vt = virtual_table()
    spec = load_specimen(str(EXAMPLES / "opensees_frame.toml"))
    cmd = make_command("earthquake", record="elcentro", peak_in=3.0)
    # the model alone, under the platen motion of a run (the loads' bookkeeping included)
    exp = run_experiment(spec, cmd, vt=vt, output_dt=0.001)
    res = exp.result
    a_x, theta = res.joint("x", "qacc"), res.joint("pitch")
    alpha = res.joint("pitch", "qacc")
    stepper = OpenSeesStepper(spec.built, vt.pivot_depth, 1e-3)
    stepper.start()
    t0 = time.perf_counter()
    for k in range(len(a_x)):
        stepper.step(a_x[k], 0.0, alpha[k], theta[k])
        stepper.wrench()
    alone = (time.perf_counter() - t0) / len(a_x)
    duration = float(cmd.t[-1])
    t0 = time.perf_counter()
    run_experiment(spec, cmd, vt=vt)
    whole = time.perf_counter() - t0
    steps = duration / 1e-3
    building, _ = equivalent_building(spec, vt.pivot_depth)
    t0 = time.perf_counter()
    run_experiment(building, cmd, vt=vt)
    ref = time.perf_counter() - t0
    drift = np.abs(exp.channel("floor1_drift")).max()
    print(f"{spec.title}: El Centro at 3 in, {duration:.1f} s at the 1 kHz control step "
          f"({steps:.0f} steps); peak first-storey drift {drift:.2f} in")
    print(f"  OpenSees model alone      {1e6 * alone:7.0f} µs/step")
    print(f"  co-simulated step (all)   {1e6 * whole / steps:7.0f} µs/step   "
          f"{whole:6.1f} s   {duration / whole:5.2f}x real time")
    print(f"  vtable's shear building   {1e6 * ref / steps:7.0f} µs/step   "
          f"{ref:6.1f} s   {duration / ref:5.2f}x real time (the same table, no OpenSees)")


if __name__ == "__main__":
    main()
