"""Comparing a model with a campaign: where it fails.

Errors are dimensionless. For a run and a channel group the time-domain error is the
normalised RMS ||ŷ - y|| / ||y|| over the scored samples; the campaign error is the mean
over runs and the groups the run has (a group averages duplicate sensors: H1-H3, the two
top accelerometers, ...). Frequency-band errors compare H1 transfer functions from the
command, weighted by coherence; amplitude errors are per run (runs of different spans);
time windows locate where the residual concentrates. The noise floor is the NRMS the
sensors' noise alone would cost, estimated from redundant sensors or from the spectrum
above the response band.

A building's floors (`run_groups`). The run format's floorK_acc and floorK_disp are the
absolute x motion of floor K from the bottom; how many floors a run has is its [specimen]'s
storey count N (an SDOF frame is one storey). The top floor is the quantity the top-mass
instruments measure, so floorN_acc is one more sensor of "structure acceleration" and
floorN_disp of "structure displacement" (averaged with them as duplicate sensors are). Each
floor below the top is a group of its own, "floor K acceleration" and "floor K
displacement": different floors are different signals and are never averaged together,
and one group per floor keeps the campaign error what it was, a mean of per-group NRMS,
each floor weighing as much as the top. Floor channels above the declared N (the model has
no such floor) and every other channel no group holds are not scored; `campaign_notes` says
so, naming them.

Sample rates. Runs sampled faster than `ANALYSIS_FS` (200 Hz) are analysed at 200 Hz: every
channel is anti-alias filtered and resampled by the rational factor p/q = 200/f_s
(`scipy.signal.resample_poly`: a Kaiser-windowed FIR low-pass at the new Nyquist frequency,
zero phase, linear trend removed at the ends), so a 256 Hz run is analysed at 256·25/32 =
200 Hz and a 1 kHz run at 1000/5. Errors, the noise floor and the model's predictions are
all taken at that rate, so they stay consistent (white sensor noise loses the share above
100 Hz in both). Runs at or below 200 Hz are analysed at their own rate (the reduced model
integrates at a step dividing theirs). Below `MIN_FS` (100 Hz) a run is refused: the
analysis bands reach 30 Hz and the noise floor is read above 50 Hz.

Whether a final error is "consistent with the noise floor" (`unexplained`): sensor noise
and a systematic model error are independent, so their squared NRMS add,
err² ≈ floor² + sys². The error is called consistent with the noise when
err ≤ NOISE_FACTOR × floor (2×), i.e. when the systematic part is at most √3 ≈ 1.7 times
the noise; above that a residual remains unexplained and is localised.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import scipy.signal

from vtable import units
from vtable.errors import VtableError
from vtable.ident.tf import transfer_function
from vtable.runs.model import FORMAT_UNITS, Run

#: channel groups: name -> the format channels averaged into it (a run's floors are added by
#: `run_groups`)
GROUPS: dict[str, tuple[str, ...]] = {
    "table displacement": ("avg_hdisp", "h1_disp", "h2_disp", "h3_disp"),
    "table velocity": ("h_vel",),
    "table acceleration": ("avg_hacc",),
    "actuator force": ("h1_force", "h2_force", "h3_force"),
    "pitch": ("pitch_acc",),
    "structure acceleration": ("acc_n_ne", "acc_n_nw"),
    "structure displacement": ("pot_n_sw", "pot_n_se"),
}
_FLOOR_CHANNEL = re.compile(r"floor([1-9][0-9]*)_(acc|disp)")
_FLOOR_GROUP = re.compile(r"floor ([1-9][0-9]*) (acceleration|displacement)")


class _GroupUnits(dict):
    """GROUPS' units, and those of every floor group "floor K acceleration" (g) and
    "floor K displacement" (in) (`run_groups`; not listed when iterating)."""

    def __missing__(self, key: str) -> str:
        m = _FLOOR_GROUP.fullmatch(key) if isinstance(key, str) else None
        if m is None:
            raise KeyError(key)
        return "g" if m.group(2) == "acceleration" else "in"

    def __contains__(self, key: object) -> bool:
        return dict.__contains__(self, key) or (
            isinstance(key, str) and _FLOOR_GROUP.fullmatch(key) is not None)


#: the unit each group is shown in (the run format's unit of its channels)
GROUP_UNITS: dict[str, str] = _GroupUnits({g: FORMAT_UNITS[c[0]] for g, c in GROUPS.items()})
BANDS = ((0.0, 2.0), (2.0, 5.0), (5.0, 10.0), (10.0, 20.0), (20.0, 30.0))
HELD_OUT = 0.4  # the last 40 % of every run is held out from fitting ...
#: ... and the fits use at most the first 30 s of each run: a few parameters do not need
#: more, and every simulated second costs the fits time (a 165 s run trains on 30 s)
TRAIN_MAX_S = 30.0
ANALYSIS_FS = 200.0  # Hz: faster runs are anti-alias filtered and resampled to this rate
MIN_FS = 100.0  # Hz: slower runs cannot resolve the bands and the noise floor
NOISE_FACTOR = 2.0  # a final error <= 2 x the noise floor is consistent with the noise
UNEXPLAINED_RULE = (f"unexplained is null when the final error <= {NOISE_FACTOR:g} x the noise "
                    "floor: noise and a systematic error add in quadrature, err^2 = floor^2 + "
                    f"sys^2, so this admits a systematic part up to "
                    f"{np.sqrt(NOISE_FACTOR**2 - 1):.2f} x the noise; otherwise it gives the "
                    "ratio final error / noise floor and where the final model's residual "
                    "lives (worst channel group, its worst band, the amplitude trend, the worst "
                    "2 s window)")


def short(name: str) -> str:
    return Path(name).name


_STOREYS: dict[str, int] = {}  # the [specimen] table's repr -> its storey count


def storeys(run: Run) -> int:
    """How many floors the run's declared [specimen] has: its storeys for a shear building,
    1 for an SDOF frame (its top mass), 0 for a rigid block or a bare table."""
    key = repr(run.meta.get("specimen"))
    if key not in _STOREYS:
        from vtable.params.specimen import SDOFSpecimen, ShearBuilding

        spec = run.specimen()
        _STOREYS[key] = (len(spec.weights) if isinstance(spec, ShearBuilding)
                         else 1 if isinstance(spec, SDOFSpecimen) else 0)
    return _STOREYS[key]


def run_groups(run: Run) -> dict[str, tuple[str, ...]]:
    """The channel groups of `run`: `GROUPS`, the top floor's channels added to the
    structure groups, and a group for each floor below the top (module docstring)."""
    n = storeys(run)
    groups = dict(GROUPS)
    if n:
        groups["structure acceleration"] += (f"floor{n}_acc",)
        groups["structure displacement"] += (f"floor{n}_disp",)
    for k in range(1, n):
        groups[f"floor {k} acceleration"] = (f"floor{k}_acc",)
        groups[f"floor {k} displacement"] = (f"floor{k}_disp",)
    return groups


def analysis_run(run: Run) -> Run:
    """The run at its analysis rate (see the module docstring): unchanged at or below
    `ANALYSIS_FS`, else anti-alias filtered and resampled to it, with a note in `reports`."""
    fs = run.fs
    if fs < MIN_FS * (1 - 1e-9):
        raise VtableError(f"{run.name}: sampled at {fs:.4g} Hz; compare and diagnose need at "
                          f"least {MIN_FS:g} Hz (the analysis bands reach {BANDS[-1][1]:g} Hz "
                          "and the noise floor is read above 50 Hz)")
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


def excluded_channels(run: Run) -> list[str]:
    """The group channels a run has that are left out of its groups (missing samples)."""
    out = []
    for g, chans in run_groups(run).items():
        for c in chans:
            if run.has(c) and run.missing.get(c):
                out.append(f"{run.name}: channel {c!r} has {run.missing[c]} missing samples; "
                           f"left out of {g}")
        present = [c for c in chans if run.has(c)]
        if present and group_signal(run, g) is None:
            why = ("every channel has missing samples" if all(run.missing.get(c) for c in present)
                   else "its channels are zero throughout")
            out.append(f"{run.name}: {g} is not scored ({why})")
    return out


def unscored_channels(run: Run) -> list[str]:
    """Notes naming every channel of `run` that no channel group holds (so it is not
    scored): floor channels above the declared storeys, then all others. The command
    h_span drives the model and is not listed."""
    grouped = {c for chans in run_groups(run).values() for c in chans}
    rest = [c for c in run.channels if c not in grouped and c != "h_span"]
    n = storeys(run)
    floors = [c for c in rest if _FLOOR_CHANNEL.fullmatch(c)]
    others = [c for c in rest if c not in floors]
    out = []
    if floors:
        why = ("the [specimen] has no storeys; the model predicts no floors" if n == 0 else
               "the [specimen] declares 1 storey; the model predicts floor 1 only" if n == 1
               else f"the [specimen] declares {n} storeys; the model predicts floors 1-{n}")
        out.append(f"{run.name}: left out: {', '.join(floors)} ({why})")
    if others:
        out.append(f"{run.name}: left out: {', '.join(others)} (not scored: no channel group "
                   "holds them)")
    return out


def campaign_notes(runs: list[Run]) -> list[str]:
    """What the readers reported (Run.reports), the resampling done and the channels left
    out (missing samples, no channel group), each naming its run."""
    notes = []
    for r in runs:
        for rep in r.reports:
            notes.append(rep if short(r.name) in rep else f"{r.name}: {rep}")
        notes += excluded_channels(r)
        notes += unscored_channels(r)
    return list(dict.fromkeys(notes))


def group_signal(run: Run, group: str) -> np.ndarray | None:
    """The measured signal of a group of `run_groups(run)` (its channels without missing
    samples averaged); None when it has none or they are zero throughout."""
    chans = [c for c in run_groups(run).get(group, ()) if run.has(c) and not run.missing.get(c)]
    if not chans:
        return None
    y = np.mean([run.channels[c] for c in chans], axis=0)
    return y if np.sqrt(np.mean(y**2)) > 0 else None


def group_prediction(pred: dict[str, np.ndarray], run: Run, group: str) -> np.ndarray | None:
    """The model's prediction of a group: its channels averaged as `group_signal` averages
    the measured ones (one array predicted for several sensors counts once per sensor)."""
    chans = [c for c in run_groups(run).get(group, ())
             if run.has(c) and not run.missing.get(c) and c in pred]
    if not chans:
        return None
    arrays = [pred[c] for c in chans]
    first = arrays[0]
    if all(a is first for a in arrays):  # the lumped model predicts one for all
        return first
    return np.mean(arrays, axis=0)


def segments(run: Run) -> tuple[slice, slice]:
    """Training (the first 60 %, at most `TRAIN_MAX_S`) and held-out (the last 40 %)
    samples of a run."""
    n = len(run.time)
    cut = round(n * (1 - HELD_OUT))
    return slice(0, min(cut, round(TRAIN_MAX_S * run.fs) + 1)), slice(cut, n)


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


def channel_noise(run: Run, f_min: float = 50.0) -> dict[str, float]:
    """Each group channel's sensor noise σ (absolute, the channel's unit), stationary over
    the run.

    From redundant sensors (H1 and H3 displacements, the two top accelerometers, the two
    potentiometers): σ = std(a - b)/√2 for both. A channel without a pair takes the median
    relative noise σ/RMS of the pairs times its own RMS (a sensor's noise is a fraction of
    the range it is set to); with no pair at all, the spectrum above `f_min` (where the
    response is negligible) gives σ² = mean PSD × bandwidth.
    """
    import scipy.signal

    sigma: dict[str, float] = {}
    rel: list[float] = []
    for a, b in PAIRS:
        if all(run.has(c) and not run.missing.get(c) for c in (a, b)):
            ya, yb = run.channels[a], run.channels[b]
            rms = np.sqrt(0.5 * (np.mean(ya**2) + np.mean(yb**2)))
            if rms > 0:
                s = float(np.std(ya - yb) / np.sqrt(2))
                sigma[a] = sigma[b] = s
                rel.append(s / rms)
    fallback = float(np.median(rel)) if rel else None
    for chans in run_groups(run).values():
        for c in chans:
            if c in sigma or not run.has(c) or run.missing.get(c):
                continue
            y = run.channels[c]
            if fallback is not None:
                sigma[c] = fallback * float(np.sqrt(np.mean(y**2)))
                continue
            f, P = scipy.signal.welch(y, fs=run.fs, nperseg=min(512, len(y)))
            hi = f >= f_min
            if hi.any():
                sigma[c] = float(np.sqrt(np.mean(P[hi]) * run.fs / 2))
    return sigma


def group_noise(run: Run, f_min: float = 50.0) -> dict[str, float]:
    """Each channel group's noise σ per sample (the group's unit): its m sensors averaged,
    √(Σ σ_c²)/m with each σ_c from `channel_noise`."""
    sigma = channel_noise(run, f_min)
    out = {}
    for g, chans in run_groups(run).items():
        used = [c for c in chans if c in sigma and run.has(c) and not run.missing.get(c)]
        if used:
            out[g] = float(np.sqrt(sum(sigma[c] ** 2 for c in used)) / len(used))
    return out


def noise_floor(runs: list[Run], scored: str = "held", f_min: float = 50.0) -> float:
    """The error the sensor noise alone would cost, measured as the error is: the mean
    over runs and groups of σ_group / RMS(group signal) on the scored segments ("held":
    the held-out last 40 % of every run, "train", or "all"), σ_group from `group_noise`.

    The noise is stationary but the signal is not: an earthquake's decaying tail, held out,
    carries the same noise on a weaker signal, so its floor is higher than the whole run's.
    """
    vals = []
    for r in runs:
        sl = dict(zip(("train", "held"), segments(r), strict=True)).get(scored, slice(None))
        for g, s in group_noise(r, f_min).items():
            y = group_signal(r, g)
            if y is None:
                continue
            rms = float(np.sqrt(np.mean(y[sl] ** 2)))
            vals.append(min(s / rms, 1.0) if rms > 0 else 1.0)
    return float(np.mean(vals)) if vals else 0.0


@dataclass(frozen=True)
class Gain:
    """What a candidate model gains over the current one on the held-out segments, on the
    squared scale where sensor noise and a systematic error add (`held_out_gain`).

    `e2_current`, `e2_candidate`: the mean over runs and groups of the squared NRMS error;
    `f2`: the sensor noise alone on the same scale; `se`: the standard deviation of the
    gain that the held-out noise itself produces, for these two predictions.
    """

    e2_current: float
    e2_candidate: float
    f2: float
    se: float

    @property
    def gain(self) -> float:
        return self.e2_current - self.e2_candidate

    @property
    def z(self) -> float:
        """The gain in standard errors of the noise (a likelihood-ratio z statistic)."""
        return self.gain / self.se if self.se > 0 else (np.inf if self.gain > 0 else 0.0)

    @property
    def systematic(self) -> float:
        """The current model's systematic residual, e² - floor² (≥ 0)."""
        return max(self.e2_current - self.f2, 0.0)

    @property
    def share(self) -> float:
        """The share of the current systematic residual the candidate removes."""
        return self.gain / self.systematic if self.systematic > 0 else np.inf


def held_out_gain(current: dict[str, dict[str, np.ndarray]],
                  candidate: dict[str, dict[str, np.ndarray]], runs: list[Run],
                  noise: dict[str, dict[str, float]]) -> Gain:
    """`Gain` of `candidate`'s predictions over `current`'s on the held-out segments.

    For a run and group with held-out measurement y = s + n (n white, σ per sample from
    `noise`), the squared NRMS of a prediction ŷ is ||y - ŷ||²/||y||². Both predictions
    were fitted on the training segments, so the held-out noise is independent of them and
    the difference of the two squared errors is its systematic part plus 2 n·(ŷ_c - ŷ)/||y||²,
    a Gaussian term of variance 4 σ² ||ŷ_c - ŷ||²/||y||⁴: summed over groups, that is the
    noise's share of the gain, `se`.
    """
    e_cur, e_cand, f2, var = [], [], [], 0.0
    for r in runs:
        _, ho = segments(r)
        sig = noise.get(r.name, {})
        for g in run_groups(r):
            y = group_signal(r, g)
            a = group_prediction(current[r.name], r, g)
            b = group_prediction(candidate[r.name], r, g)
            if y is None or a is None or b is None:
                continue
            y, a, b = y[ho], a[ho], b[ho]
            yy = float(np.sum(y**2))
            if not yy > 0:
                continue
            e_cur.append(nrms(a, y) ** 2)
            e_cand.append(nrms(b, y) ** 2)
            s = sig.get(g, 0.0)
            f2.append(s**2 * len(y) / yy)
            d = b - a
            var += 4 * s**2 * float(np.sum(d**2)) / yy**2 if np.all(np.isfinite(d)) else 0.0
    k = max(len(e_cur), 1)
    return Gain(float(np.sum(e_cur)) / k, float(np.sum(e_cand)) / k, float(np.sum(f2)) / k,
                float(np.sqrt(var)) / k)


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
        for g in run_groups(r):
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


def mils(x_m: float) -> str:
    """A command amplitude in metres as mils (1 mil = 0.001 in = 25.4 µm)."""
    v = 1000 * units.from_si(x_m, "in")
    return f"{v:.0f}" if v >= 10 else f"{v:.2g}"


def amplitude_trend(cmp: Comparison, group: str | None = None) -> str:
    """How a group's (or the mean) error changes with the command's RMS span across runs."""
    pts = []
    for name, a, e in cmp.amplitude:
        if group is not None:
            e = cmp.per_run.get(name, {}).get(group)
        if e is not None:
            pts.append((a, e))
    if len({round(a, 9) for a, _ in pts}) < 2:
        return "one command amplitude only (no amplitude trend can be read)"
    pts.sort()
    (a0, e0), (a1, e1) = pts[0], pts[-1]
    span = f"{e0:.1%} at {mils(a0)} mil rms, {e1:.1%} at {mils(a1)} mil rms"
    if e1 > 1.25 * e0:
        return f"largest at the largest spans ({span})"
    if e0 > 1.25 * e1:
        return f"largest at the smallest spans ({span})"
    return f"no clear amplitude trend ({span})"


def unexplained(cmp: Comparison) -> dict[str, Any] | None:
    """None when cmp.error <= NOISE_FACTOR x the noise floor, else the ratio and where the
    residual lives (UNEXPLAINED_RULE)."""
    floor = cmp.noise_floor
    if floor > 0 and cmp.error <= NOISE_FACTOR * floor:
        return None
    ratio = cmp.error / floor if floor > 0 else float("inf")
    return {"ratio_to_floor": ratio, "where": residual_location(cmp)}


def residual_location(cmp: Comparison) -> str:
    """'<group>, <band>, <amplitude trend>, <time window>' of a comparison made with
    detail=True; what could not be read is said."""
    worst = cmp.worst_groups(1)
    if not worst:
        return "no channel group was scored"
    g, e = worst[0]
    wb = cmp.worst_band(g)
    band = f"worst band {wb[0]} ({wb[1]:.1%})" if wb else "no band resolved (no coherent band)"
    if cmp.windows:
        name, t0, t1, ew = max(cmp.windows, key=lambda x: x[3])
        window = f"worst 2 s window {t0:.1f}-{t1:.1f} s of {short(name)} ({ew:.1%})"
    else:
        window = "no time window located (runs shorter than 2 s)"
    return f"{g} ({e:.1%}), {band}, {amplitude_trend(cmp, g)}, {window}"


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
            f"{e:.1%} at {mils(a)} mil rms" for _, a, e in amp))
    if cmp.windows:
        name, t0, t1, e = max(cmp.windows, key=lambda x: x[3])
        parts.append(f"worst 2 s window {t0:.1f}-{t1:.1f} s of {short(name)} ({e:.1%})")
    parts.append(f"noise floor {cmp.noise_floor:.1%}")
    return "; ".join(parts)
