"""Frequency response of the 8-state two-directional model (eq 8.16) on 512 frequencies:
vtable's modal evaluation (with its direct-solve fallback) vs python-control's
`frequency_response`. Prints the times, the speed ratios and the agreement.

The three timings are interleaved round by round (best of each over the rounds), so a
machine loaded by other work slows both sides alike and the printed ratio is one run's.
Both sides run with one BLAS thread unless OPENBLAS_NUM_THREADS says otherwise: the
matrices are 8 x 8, and on a loaded machine extra BLAS threads only contend.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy is imported

import timeit

import numpy as np

from vtable.analytic import TwoDirectionalTable
from vtable.analytic.pitch import two_directional

ROUNDS = 15


def main() -> None:
    import control

    model = TwoDirectionalTable(two_directional(21.0))
    sys = model.to_control()
    f = np.geomspace(0.1, 50.0, 512)
    w = 2 * np.pi * f
    ours = model.freqresp(f)
    resp = control.frequency_response(sys, w)
    theirs = np.moveaxis(np.asarray(resp.frdata if hasattr(resp, "frdata")
                                    else resp.fresp), -1, 0)
    err = np.max(np.abs(ours - theirs) / np.maximum(np.abs(theirs), 1e-300))
    single = np.max(np.abs(model.freqresp(f, "x_t", "x_c") - theirs[:, 0, 0]))

    runs = {"ctrl": (lambda: control.frequency_response(sys, w), 5),
            "all": (lambda: model.freqresp(f), 50),
            "one": (lambda: model.freqresp(f, "x_t", "x_c"), 200)}
    best = dict.fromkeys(runs, np.inf)
    for _ in range(ROUNDS):
        for k, (fn, number) in runs.items():
            best[k] = min(best[k], timeit.timeit(fn, number=number) / number)
    t_ctrl, t_all, t_one = best["ctrl"], best["all"], best["one"]
    print(f"model: {model.title}; {len(model.states)} states, {len(model.outputs)} outputs x "
          f"{len(model.inputs)} inputs, {len(f)} frequencies; BLAS threads "
          f"{os.environ['OPENBLAS_NUM_THREADS']}")
    print(f"python-control {control.__version__}: {t_ctrl * 1e3:8.3f} ms")
    print(f"vtable all pairs:        {t_all * 1e3:8.3f} ms   ({t_ctrl / t_all:5.1f}x faster)")
    print(f"vtable one pair x_t/x_c: {t_one * 1e3:8.3f} ms   ({t_ctrl / t_one:5.1f}x faster)")
    print(f"max relative difference: {err:.2e} (one pair, absolute: {single:.2e})")


if __name__ == "__main__":
    main()
