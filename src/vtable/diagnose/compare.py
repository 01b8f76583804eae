"""Comparing a model with a campaign: where it fails.

Errors are dimensionless. For a run and a channel group the time-domain error is the
normalised RMS ||ŷ - y|| / ||y|| over the scored samples; the campaign error is the mean
over runs and the groups the run has (a group averages duplicate sensors: H1-H3, the two
top accelerometers, ...). Frequency-band errors compare H1 transfer functions from the
command, weighted by coherence; amplitude errors are per run (runs of different spans);
time windows locate where the residual concentrates. The noise floor is the NRMS the
sensors' noise alone would cost, estimated from redundant sensors or from the spectrum
above the response band.

The pieces live by job: channel groups (`groups`), the analysis rate and segments
(`sampling`), the sensor noise (`noise`), the error statistics (`statistics`) and the words
(`prose`); their names are importable from here as well.
"""

from __future__ import annotations

import numpy as np
import scipy.signal

from vtable.diagnose.groups import (
    GROUP_UNITS,
    GROUPS,
    campaign_notes,
    excluded_channels,
    group_prediction,
    group_signal,
    run_groups,
    short,
    storeys,
    unscored_channels,
)
from vtable.diagnose.noise import (
    NOISE_FACTOR,
    PAIRS,
    UNEXPLAINED_RULE,
    channel_noise,
    group_noise,
    noise_floor,
)
from vtable.diagnose.prose import (
    amplitude_trend,
    localisation_text,
    mils,
    residual_location,
    unexplained,
)
from vtable.diagnose.sampling import (
    ANALYSIS_FS,
    BANDS,
    HELD_OUT,
    MIN_FS,
    TRAIN_MAX_S,
    analysis_run,
    segments,
)
from vtable.diagnose.statistics import Comparison, Gain, held_out_gain, nrms
from vtable.display import run_family
from vtable.errors import VtableError
from vtable.ident.tf import transfer_function, welch_kw
from vtable.runs.model import Run

__all__ = ["ANALYSIS_FS", "BANDS", "GROUPS", "GROUP_UNITS", "HELD_OUT", "MIN_FS",
           "NOISE_FACTOR", "PAIRS", "TRAIN_MAX_S", "UNEXPLAINED_RULE", "Comparison", "Gain",
           "amplitude_trend", "analysis_run", "campaign_notes", "channel_noise", "compare",
           "excluded_channels", "group_noise", "group_prediction", "group_signal",
           "held_out_gain", "localisation_text", "mils", "noise_floor", "nrms",
           "residual_location", "run_groups", "segments", "short", "storeys",
           "unexplained", "unscored_channels"]


def compare(pred: dict[str, dict[str, np.ndarray]], runs: list[Run], *, scored: str = "held",
            floor: float | None = None, detail: bool = False,
            memo: dict | None = None) -> Comparison:
    """Errors of predictions {run name: channels} on `runs` (scored on the held-out
    segments, the training ones or "all"). `memo`: where `detail` keeps the measured
    side of its band errors between calls on the same runs (a diagnosis localises every
    round's model on them: only the prediction's cross-spectrum is new)."""
    per_run: dict[str, dict[str, float]] = {}
    all_errs = []
    for r in runs:
        tr, ho = segments(r)
        sl = {"held": ho, "train": tr, "all": slice(None)}[scored]
        errs = {}
        for g in run_groups(r):
            y = group_signal(r, g)
            yhat = group_prediction(pred[r.name], r, g)
            if y is None or yhat is None:
                continue
            errs[g] = nrms(yhat[sl], y[sl])
        per_run[r.name] = errs
        all_errs += list(errs.values())
    cmp = Comparison(float(np.mean(all_errs)), per_run,
                     noise_floor(runs, scored) if floor is None else floor)
    if detail:
        _localise(cmp, pred, runs, {} if memo is None else memo)
    return cmp


def _localise(cmp: Comparison, pred, runs: list[Run], memo: dict) -> None:
    """Band errors (coherence-weighted TF differences from the command), per-run
    amplitude, and the 2 s windows carrying the most residual; the measured spectra of
    each run (its command's auto-spectrum, each group's H1) kept in `memo` by its name."""
    bands: dict[str, dict[str, list[float]]] = {}
    for r in runs:
        if not r.has("h_span"):
            continue
        x = r.channel("h_span")
        n = min(1024, 2 ** int(np.log2(len(x) / 2)))
        kw = welch_kw(r.fs, n)
        measured = memo.setdefault(r.name, {})
        if "G_xx" not in measured:
            measured["G_xx"] = scipy.signal.welch(x, **kw)[1]
        yhats = {}
        for g in run_groups(r):
            yhat = group_prediction(pred[r.name], r, g)
            if yhat is None:
                continue
            if yhat.shape != x.shape:
                raise VtableError(f"{r.name}: the prediction of {g} has {len(yhat)} samples, "
                                  f"the run {len(x)}")
            if g not in measured:
                y = group_signal(r, g)
                measured[g] = None if y is None else transfer_function(x, y, r.fs, n)
            if measured[g] is not None:
                yhats[g] = yhat
        Hs: np.ndarray | list = []
        if yhats:  # the model's H1 of every group in one call (scipy's cost is per call)
            with np.errstate(divide="ignore", invalid="ignore"):
                Hs = scipy.signal.csd(x, np.array(list(yhats.values())), **kw)[1] \
                    / measured["G_xx"]
        for g, H in zip(yhats, Hs, strict=True):
            tm = measured[g]
            for lo, hi in BANDS:
                sel = (tm.f > max(lo, 0.2)) & (tm.f <= hi) & np.isfinite(tm.H) & \
                      np.isfinite(H)
                if not sel.any():
                    continue
                w = tm.coherence[sel]
                num = np.sum(w * np.abs(H[sel] - tm.H[sel]) ** 2)
                den = np.sum(w * np.abs(tm.H[sel]) ** 2) or 1.0
                bands.setdefault(g, {}).setdefault(f"{lo:g}-{hi:g} Hz", []).append(
                    float(np.sqrt(num / den)))
        cmp.display = run_family(r)
        cmp.amplitude.append((r.name, float(np.sqrt(np.mean(x**2))),
                              float(np.mean(list(cmp.per_run[r.name].values())))))
        res = []
        for g in run_groups(r):
            y = group_signal(r, g)
            yhat = group_prediction(pred[r.name], r, g)
            if y is not None and yhat is not None:
                res.append(((yhat - y) / np.sqrt(np.mean(y**2))) ** 2)
        if res:
            e = np.mean(res, axis=0)
            w = int(2.0 * r.fs)
            if len(e) >= w:
                csum = np.convolve(e, np.ones(w) / w, mode="valid")
                i = int(np.argmax(csum))
                cmp.windows.append((r.name, float(r.time[i] - r.time[0]),
                                    float(r.time[i] - r.time[0] + 2.0),
                                    float(np.sqrt(csum[i]))))
    cmp.bands = {g: {b: float(np.mean(v)) for b, v in d.items()} for g, d in bands.items()}

