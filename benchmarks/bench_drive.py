"""Speed of `vtable drive` (issue 20's figure: a drive for a 40 s record in <= 30 s):
the SDOF frame with pitch on the EERC table, a three-run campaign (2 x 20 s random and
El Centro, 200 Hz, 2 % noise) made by the independent truth simulator (tests/truth) with
the declaration off; a 40 s synthetic Kanai-Tajimi record as the target. Printed: the
calibration, the drive with its baselines, and the whole verb as a user runs it.

    python benchmarks/bench_drive.py"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import truth

from vtable.diagnose.model import TableModel
from vtable.drive import compensate, read_target
from vtable.ident.drive import align
from vtable.ident.structure import effective_height
from vtable.runs import campaign
from vtable.verbs.compensation import drive

IN = 0.0254


def main() -> None:
    folder = Path(tempfile.mkdtemp(prefix="vtable-bench-drive-"))
    spec = truth.sdof(68.0, 219.0, 2.87, 0.01)
    paths = [str(p) for p in truth.campaign(folder / "c", truth.eerc_table(pitch="hybrid"),
                                            spec, truth.perturb(spec, seed=5), fs=200.0,
                                            duration_s=20.0, quake_peak_in=2.0)]
    # a 40 s target: the 25 s Kanai-Tajimi motion slowed to 34 s, 4 s of pads, 2 s of rest
    cmd = truth.earthquake_command("synthetic", peak_in=2.0, seed=4, fs=200.0,
                                   time_scale=25.0 / 34.0)
    tgt = folder / "target.csv"
    rows = "\n".join(f"{t:.6f},{x / IN:.9g}" for t, x in zip(cmd.t, cmd.x, strict=True))
    tgt.write_text("time,displacement\n" + rows + "\n")
    target = read_target(str(tgt))
    print(f"target: {target.t[-1]:.1f} s at {target.fs:g} Hz ({len(target.t)} samples)")
    runs = [align(r) for r in campaign(paths)]
    t0 = time.perf_counter()
    model = TableModel(["pitch_flexibility"]).fit(runs)
    t1 = time.perf_counter()
    r = compensate(model, target, effective_height(runs[0]))
    t2 = time.perf_counter()
    print(f"calibration (3 runs, 60 s): {t1 - t0:.2f} s")
    print(f"drive with its three baselines: {t2 - t1:.2f} s "
          f"({len(r.history) - 1} iterations, model NRMS {100 * r.history[-1]:.2f} %)")
    t3 = time.perf_counter()
    drive(paths, str(tgt), str(folder / "drive"), with_=["pitch_flexibility"])
    t4 = time.perf_counter()
    print(f"vtable drive, whole (read, calibrate, drive, write): {t4 - t3:.2f} s "
          f"(target <= 30 s)")
    print(f"drive peak {np.max(np.abs(r.drive.drive)) / IN:.3f} in")


if __name__ == "__main__":
    main()
