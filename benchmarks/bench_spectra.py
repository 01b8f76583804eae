"""Response spectrum of El Centro (0.01 s, 5 %, 200 periods 0.02-5 s): vtable's compiled
Nigam-Jennings recurrence beside eqsig's pseudo_response_spectra (if installed)."""

from __future__ import annotations

import timeit

import numpy as np

from vtable.signals.records import el_centro
from vtable.signals.spectra import response_spectrum


def main() -> None:
    rec = el_centro()
    periods = np.geomspace(0.02, 5.0, 200)
    response_spectrum(rec.acc, rec.dt, periods)  # compile
    ours = min(timeit.repeat(lambda: response_spectrum(rec.acc, rec.dt, periods),
                             number=10, repeat=5)) / 10
    print(f"vtable response_spectrum: {ours * 1e3:.2f} ms")
    try:
        from eqsig.sdof import pseudo_response_spectra
    except ImportError:
        print("eqsig not installed: pip install eqsig for the side-by-side figure")
        return
    theirs = min(timeit.repeat(lambda: pseudo_response_spectra(rec.acc, rec.dt, periods, 0.05),
                               number=2, repeat=3)) / 2
    print(f"eqsig pseudo_response_spectra: {theirs * 1e3:.2f} ms")
    print(f"speed-up: {theirs / ours:.1f}x (target >= 10x)")


if __name__ == "__main__":
    main()
