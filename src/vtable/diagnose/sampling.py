"""The analysis's rate, bands and segments: what every error, noise floor and prediction of
the diagnosis is taken on.

Sample rates. Runs sampled faster than `ANALYSIS_FS` (200 Hz) are analysed at 200 Hz: every
channel is anti-alias filtered and resampled by the rational factor p/q = 200/f_s
(`scipy.signal.resample_poly`: a Kaiser-windowed FIR low-pass at the new Nyquist frequency,
zero phase, linear trend removed at the ends), so a 256 Hz run is analysed at 256·25/32 =
200 Hz and a 1 kHz run at 1000/5. Errors, the noise floor and the model's predictions are
all taken at that rate, so they stay consistent (white sensor noise loses the share above
100 Hz in both). Runs at or below 200 Hz are analysed at their own rate (the reduced model
integrates at a step dividing theirs). Below `MIN_FS` (100 Hz) a run is refused: the
analysis bands reach 30 Hz and the noise floor is read above 50 Hz.

Training and held-out segments (`segments`): the fits use the first 60 % of every run (at
most its first `TRAIN_MAX_S`), the scores the last 40 %.
"""

from __future__ import annotations

import dataclasses
from fractions import Fraction

import numpy as np
import scipy.signal

from vtable.errors import VtableError
from vtable.runs.model import Run

BANDS = ((0.0, 2.0), (2.0, 5.0), (5.0, 10.0), (10.0, 20.0), (20.0, 30.0))
HELD_OUT = 0.4  # the last 40 % of every run is held out from fitting ...
#: ... and the fits use at most the first 30 s of each run: a few parameters do not need
#: more, and every simulated second costs the fits time (a 165 s run trains on 30 s)
TRAIN_MAX_S = 30.0
#: a candidate's screen (`vtable.diagnose.projected`) fits on the first half of each run's
#: training segment: whether an effect lowers the training cost by 1 % shows there at half
#: the simulations, and a candidate that passes is fitted on the whole segment
SCREEN_SHARE = 0.5
ANALYSIS_FS = 200.0  # Hz: faster runs are anti-alias filtered and resampled to this rate
MIN_FS = 100.0  # Hz: slower runs cannot resolve the bands and the noise floor
#: Hz: the fastest run resampled (by a ratio of denominator at most 1000: 200 Hz from 200 kHz)
MAX_FS = 1000 * ANALYSIS_FS


def analysis_run(run: Run) -> Run:
    """The run at its analysis rate (see the module docstring): unchanged at or below
    `ANALYSIS_FS`, else anti-alias filtered and resampled to it, with a note in `reports`."""
    fs = run.fs
    if fs < MIN_FS * (1 - 1e-9):
        raise VtableError(f"{run.name}: sampled at {fs:.4g} Hz; compare and diagnose need at "
                          f"least {MIN_FS:g} Hz (the analysis bands reach {BANDS[-1][1]:g} Hz "
                          "and the noise floor is read above 50 Hz)")
    if fs > MAX_FS:
        raise VtableError(f"{run.name}: sampled at {fs:.4g} Hz (column 'time' steps "
                          f"{1 / fs:.3g} s); compare and diagnose resample runs to "
                          f"{ANALYSIS_FS:g} Hz from at most {MAX_FS:g} Hz: is 'time' in "
                          "seconds?")
    ratio = Fraction(ANALYSIS_FS / fs).limit_denominator(1000)
    up, down = ratio.numerator, ratio.denominator
    if up >= down:
        return run
    fs_a = fs * up / down
    n = len(run.time)
    m = int(np.floor((n - 1) * up / down + 1e-9)) + 1
    channels, missing = {}, dict(run.missing)
    for c, v in run.channels.items():
        bad = int(np.count_nonzero(~np.isfinite(v)))
        if missing.get(c) or bad:
            missing[c] = missing.get(c) or bad
            channels[c] = np.full(m, np.nan)  # left out of its group; never filled in
        else:
            channels[c] = scipy.signal.resample_poly(v, up, down, padtype="line")[:m]
    note = (f"{run.name}: sampled at {fs:.6g} Hz, analysed at {fs_a:.6g} Hz (anti-alias "
            f"filtered and resampled by {up}/{down})")
    return dataclasses.replace(run, time=run.time[0] + np.arange(m) / fs_a, channels=channels,
                               missing=missing, reports=[*run.reports, note])



def segments(run: Run, whole: bool = False, share: float = 1.0) -> tuple[slice, slice]:
    """Training (the first 60 %, at most `TRAIN_MAX_S` unless `whole`; its first `share`,
    e.g. `SCREEN_SHARE`) and held-out (the last 40 %) samples of a run."""
    n = len(run.time)
    cut = round(n * (1 - HELD_OUT))
    stop = cut if whole else min(cut, round(TRAIN_MAX_S * run.fs) + 1)
    if share < 1.0:
        stop = max(2, round(stop * share))
    return slice(0, stop), slice(cut, n)

