"""The §9.9 comparison: PSV spectra of the §9.2-processed El Centro through the five
models of §9.4 (60 periods, 0.05-3 s) for the Table 8.1 frame: time per set of spectra."""

from __future__ import annotations

import time

import numpy as np

from vtable.params import presets
from vtable.signals.processing import process_record
from vtable.signals.records import el_centro
from vtable.studies.interaction import psv_spectra


def main() -> None:
    spec = presets.specimen("table8_1")
    cmd = process_record(el_centro())
    periods = np.geomspace(0.05, 3.0, 60)
    psv_spectra(spec, cmd.acceleration, cmd.dt, periods[:2])  # compile
    t0 = time.perf_counter()
    psv = psv_spectra(spec, cmd.acceleration, cmd.dt, periods)
    dt = time.perf_counter() - t0
    print(f"5 models x {len(periods)} periods x {len(cmd.acceleration)} steps: {dt:.2f} s "
          f"({1e3 * dt / (5 * len(periods)):.1f} ms per model and period)")
    i = np.argmin(abs(periods - 1 / spec.frequency))
    print("PSV near T_s (in/s): " + ", ".join(f"{k} {v[i] / 0.0254:.1f}" for k, v in psv.items()))


if __name__ == "__main__":
    main()
