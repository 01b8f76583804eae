"""Reading a long run: 600 s at 1 kHz, time + 40 channels (24.6 million samples, 197 MB
of float64), as RUN.csv + RUN.toml and as HDF5. Each file is read in a fresh Python
process that reports its wall time and its peak resident memory (VmHWM), with the
same process's peak after the imports subtracted (target: the CSV reads in
<= 1 GB, about twice the samples). Exact round trip checked on the CSV.

    python benchmarks/bench_read.py [--seconds 600] [--rate 1000] [--channels 40] [--dir D]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

CHILD = r"""
import json, resource, sys, time
import numpy as np
import h5py
from vtable.runs import read_any


def hwm_kib():
    # peak RSS of this process image (VmHWM; getrusage's maxrss would include the
    # parent's peak, inherited at fork)
    try:
        for line in open("/proc/self/status"):
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


base = hwm_kib()
t0 = time.perf_counter()
run = read_any(sys.argv[1])
wall = time.perf_counter() - t0
peak = hwm_kib()
check = float(np.nansum([v[::997].sum() for v in run.channels.values()]))
print(json.dumps({"wall_s": wall, "peak_kib": peak, "base_kib": base, "n": len(run.time),
                  "channels": len(run.channels), "check": check}))
"""


def _names(k: int) -> list[str]:
    from vtable.runs.model import FORMAT_UNITS

    names = [h for h in FORMAT_UNITS if h != "pitch_disp"]
    i = 1
    while len(names) < k:
        names.append(f"floor{i}_acc")
        i += 1
    return names[:k]


def make_run(seconds: float, rate: float, channels: int):
    from vtable import units
    from vtable.runs.model import FORMAT_UNITS, Run

    n = round(seconds * rate) + 1
    rng = np.random.default_rng(1)
    names = _names(channels)
    # small, plausible values in each channel's unit (0.1 in, 0.1 g, 0.1 kip, ...)
    ch = {h: units.to_si(0.1 * rng.standard_normal(n), FORMAT_UNITS[h]) for h in names}
    return Run("bench", np.arange(n) / rate, ch, {h: FORMAT_UNITS[h] for h in names},
               {"title": "bench_read", "table": {"preset": "eerc"}})


def read_in_child(path: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", CHILD, str(path)], capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=600.0)
    ap.add_argument("--rate", type=float, default=1000.0)
    ap.add_argument("--channels", type=int, default=40)
    ap.add_argument("--dir", default=None, help="folder for the files [a temporary one]")
    a = ap.parse_args()

    from vtable.runs import read_run, write_hdf5, write_run

    with tempfile.TemporaryDirectory(dir=a.dir) as tmp:
        run = make_run(a.seconds, a.rate, a.channels)
        samples = 8 * len(run.time) * (len(run.channels) + 1)
        print(f"run: {a.seconds:g} s at {a.rate:g} Hz, time + {len(run.channels)} channels = "
              f"{samples / 1e6:.0f} MB of float64")
        t0 = time.perf_counter()
        csv, _ = write_run(run, Path(tmp) / "bench")
        t1 = time.perf_counter()
        h5 = write_hdf5(run, Path(tmp) / "bench.h5")
        t2 = time.perf_counter()
        print(f"write: CSV {csv.stat().st_size / 1e6:.0f} MB in {t1 - t0:.1f} s, "
              f"HDF5 {h5.stat().st_size / 1e6:.0f} MB in {t2 - t1:.1f} s")
        for label, path in (("CSV", Path(tmp) / "bench.toml"), ("HDF5", h5)):
            r = read_in_child(path)
            extra = (r["peak_kib"] - r["base_kib"]) * 1024
            print(f"read {label:4s}: {r['wall_s']:6.1f} s, peak RSS {r['peak_kib'] / 2**20:.2f} "
                  f"GiB ({extra / 1e6:.0f} MB above the imports = {extra / samples:.2f} x the "
                  f"samples)")
        back = read_run(Path(tmp) / "bench.toml")
        exact = all(np.array_equal(back.channels[h], run.channels[h], equal_nan=True)
                    for h in run.channels) and np.array_equal(back.time, run.time)
        print(f"CSV round trip exact: {exact}")


if __name__ == "__main__":
    main()
