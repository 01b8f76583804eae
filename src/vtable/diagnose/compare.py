"""Comparing a model with a campaign: where it fails.

Errors are dimensionless. For a run and a channel group the time-domain error is the
normalised RMS ||ŷ - y|| / ||y|| over the scored samples; the campaign error is the mean
over runs and the groups the run has (a group averages duplicate sensors: H1-H3, the two
top accelerometers, ...). Frequency-band errors compare H1 transfer functions from the
command, weighted by coherence; amplitude errors are per run (runs of different spans);
time windows locate where the residual concentrates. The noise floor is the NRMS the
sensors' noise alone would cost, estimated from the spectrum above the response band.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from vtable.ident.tf import transfer_function
from vtable.runs.model import Run

#: channel groups: name -> the format channels averaged into it
GROUPS: dict[str, tuple[str, ...]] = {
    "table displacement": ("avg_hdisp", "h1_disp", "h2_disp", "h3_disp"),
    "table velocity": ("h_vel",),
    "table acceleration": ("avg_hacc",),
    "actuator force": ("h1_force", "h2_force", "h3_force"),
    "pitch": ("pitch_acc",),
    "structure acceleration": ("acc_n_ne", "acc_n_nw"),
    "structure displacement": ("pot_n_sw", "pot_n_se"),
}
BANDS = ((0.0, 2.0), (2.0, 5.0), (5.0, 10.0), (10.0, 20.0), (20.0, 30.0))
HELD_OUT = 0.4  # the last 40 % of every run is held out from fitting


def group_signal(run: Run, group: str) -> np.ndarray | None:
    chans = [c for c in GROUPS[group] if run.has(c) and not run.missing.get(c)]
    if not chans:
        return None
    y = np.mean([run.channels[c] for c in chans], axis=0)
    return y if np.sqrt(np.mean(y**2)) > 0 else None


def group_prediction(pred: dict[str, np.ndarray], run: Run, group: str) -> np.ndarray | None:
    chans = [c for c in GROUPS[group] if run.has(c) and not run.missing.get(c) and c in pred]
    return np.mean([pred[c] for c in chans], axis=0) if chans else None


def segments(run: Run) -> tuple[slice, slice]:
    """Training (first 60 %) and held-out (last 40 %) samples of a run."""
    n = len(run.time)
    cut = round(n * (1 - HELD_OUT))
    return slice(0, cut), slice(cut, n)


def nrms(yhat: np.ndarray, y: np.ndarray) -> float:
    if not np.all(np.isfinite(yhat)):
        return 10.0
    return float(np.sqrt(np.sum((yhat - y) ** 2) / np.sum(y**2)))


@dataclass
class Comparison:
    """Errors of one model on a campaign."""

    error: float  # campaign error on the scored segments
    per_run: dict[str, dict[str, float]]  # run -> group -> NRMS
    noise_floor: float
    bands: dict[str, dict[str, float]] = field(default_factory=dict)  # group -> band -> err
    windows: list[tuple[str, float, float, float]] = field(default_factory=list)
    amplitude: list[tuple[str, float, float]] = field(default_factory=list)

    def worst_groups(self, k: int = 2) -> list[tuple[str, float]]:
        agg: dict[str, list[float]] = {}
        for errs in self.per_run.values():
            for g, e in errs.items():
                agg.setdefault(g, []).append(e)
        return sorted(((g, float(np.mean(v))) for g, v in agg.items()), key=lambda x: -x[1])[:k]

    def worst_band(self, group: str) -> tuple[str, float] | None:
        b = self.bands.get(group)
        return max(b.items(), key=lambda x: x[1]) if b else None


#: redundant sensors measuring the same quantity (their difference is noise)
PAIRS = (("h1_disp", "h3_disp"), ("acc_n_ne", "acc_n_nw"), ("pot_n_sw", "pot_n_se"))


def noise_floor(runs: list[Run], f_min: float = 50.0) -> float:
    """The error the sensor noise alone would cost: mean over runs and groups of
    σ_noise/RMS(group signal).

    The noise is estimated from redundant sensors (H1 and H3 displacements, the two top
    accelerometers, the two potentiometers): σ = std(a - b)/√2, relative to each sensor's
    RMS; a group averaging m sensors has σ/√m. Groups without a pair take the median
    relative noise of the pairs; with no pair at all, the spectrum above `f_min` (where the
    response is negligible) gives σ² = mean PSD × bandwidth.
    """
    import scipy.signal

    vals = []
    for r in runs:
        rel = []
        for a, b in PAIRS:
            if all(r.has(c) and not r.missing.get(c) for c in (a, b)):
                ya, yb = r.channels[a], r.channels[b]
                rms = np.sqrt(0.5 * (np.mean(ya**2) + np.mean(yb**2)))
                if rms > 0:
                    rel.append(np.std(ya - yb) / np.sqrt(2) / rms)
        fallback = float(np.median(rel)) if rel else None
        for g, chans in GROUPS.items():
            y = group_signal(r, g)
            if y is None:
                continue
            m = sum(1 for c in chans if r.has(c) and not r.missing.get(c))
            if fallback is not None:
                pair = [v for (a, b), v in zip(PAIRS, rel, strict=False) if a in chans]
                vals.append((pair[0] if pair else fallback) / np.sqrt(m))
                continue
            f, P = scipy.signal.welch(y, fs=r.fs, nperseg=min(512, len(y)))
            hi = f >= f_min
            if hi.any():
                sigma = np.sqrt(np.mean(P[hi]) * r.fs / 2)
                vals.append(min(sigma / np.sqrt(np.mean(y**2)), 1.0))
    return float(np.mean(vals)) if vals else 0.0


def compare(pred: dict[str, dict[str, np.ndarray]], runs: list[Run], *, scored: str = "held",
            floor: float | None = None, detail: bool = False) -> Comparison:
    """Errors of predictions {run name: channels} on `runs` (scored on the held-out
    segments, the training ones or "all")."""
    per_run: dict[str, dict[str, float]] = {}
    all_errs = []
    for r in runs:
        tr, ho = segments(r)
        sl = {"held": ho, "train": tr, "all": slice(None)}[scored]
        errs = {}
        for g in GROUPS:
            y = group_signal(r, g)
            yhat = group_prediction(pred[r.name], r, g)
            if y is None or yhat is None:
                continue
            errs[g] = nrms(yhat[sl], y[sl])
        per_run[r.name] = errs
        all_errs += list(errs.values())
    cmp = Comparison(float(np.mean(all_errs)), per_run,
                     noise_floor(runs) if floor is None else floor)
    if detail:
        _localise(cmp, pred, runs)
    return cmp


def _localise(cmp: Comparison, pred, runs: list[Run]) -> None:
    """Band errors (coherence-weighted TF differences from the command), per-run
    amplitude, and the 2 s windows carrying the most residual."""
    bands: dict[str, dict[str, list[float]]] = {}
    for r in runs:
        if not r.has("h_span"):
            continue
        x = r.channel("h_span")
        n = min(1024, 2 ** int(np.log2(len(x) / 2)))
        for g in GROUPS:
            y = group_signal(r, g)
            yhat = group_prediction(pred[r.name], r, g)
            if y is None or yhat is None:
                continue
            tm = transfer_function(x, y, r.fs, n)
            tp = transfer_function(x, yhat, r.fs, n)
            for lo, hi in BANDS:
                sel = (tm.f > max(lo, 0.2)) & (tm.f <= hi) & np.isfinite(tm.H) & \
                      np.isfinite(tp.H)
                if not sel.any():
                    continue
                w = tm.coherence[sel]
                num = np.sum(w * np.abs(tp.H[sel] - tm.H[sel]) ** 2)
                den = np.sum(w * np.abs(tm.H[sel]) ** 2) or 1.0
                bands.setdefault(g, {}).setdefault(f"{lo:g}-{hi:g} Hz", []).append(
                    float(np.sqrt(num / den)))
        cmp.amplitude.append((r.name, float(np.sqrt(np.mean(x**2))),
                              float(np.mean(list(cmp.per_run[r.name].values())))))
        res = []
        for g in GROUPS:
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


def localisation_text(cmp: Comparison) -> str:
    """Where the model fails, in words and numbers."""
    parts = []
    worst = cmp.worst_groups(2)
    if worst:
        parts.append("largest errors in " + ", ".join(f"{g} ({e:.1%})" for g, e in worst))
        wb = cmp.worst_band(worst[0][0])
        if wb:
            parts.append(f"{worst[0][0]} worst at {wb[0]} ({wb[1]:.1%})")
    if len(cmp.amplitude) > 1:
        amp = sorted(cmp.amplitude, key=lambda x: x[1])
        parts.append("by command amplitude: " + ", ".join(
            f"{e:.1%} at {1000 * a / 25.4:.0f} mil rms" for _, a, e in amp))
    if cmp.windows:
        name, t0, t1, e = max(cmp.windows, key=lambda x: x[3])
        parts.append(f"worst 2 s window {t0:.1f}-{t1:.1f} s of {name.split('/')[-1]} ({e:.1%})")
    parts.append(f"noise floor {cmp.noise_floor:.1%}")
    return "; ".join(parts)
