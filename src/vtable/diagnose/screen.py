"""Whether the runs show any nonlinearity the current model misses: the screen that decides
if a nonlinear candidate is worth fitting.

A missing linear effect leaves the same residual transfer function in every run, whatever
its amplitude; a nonlinear effect the model lacks (friction, a rated flow, orifice flow,
entrained air, amplitude-dependent damping, a yielding storey, a user's force law) does
not. On the current (calibrated) model's residual r = y − ŷ of each channel group, driven
by the command x, the residual's H1 R = S_xr / S_xx (Welch frames common to the campaign;
Bendat & Piersol, *Random Data*, §9.2) is compared between every pair of runs:

    χ² = Σ |R_a − R_b|² / (Var R_a + Var R_b),   Var R ≈ (1 − γ²_xr) S_rr / (n_d S_xx),

over the lines where both commands have power in the analysis bands; a linear model gives
χ² ≈ L (one per line), so z = (χ² − L) / √(c L) (c = `LINE_CORRELATION`: the lines of
half-overlapping Hann frames are not independent) measures the amplitude dependence in
standard deviations.

z above `Z_SCREEN` anywhere, or runs whose commands do not differ in amplitude enough to
tell (`AMPLITUDES`; one run), and every nonlinear candidate is fitted as before; z below
it everywhere, and a nonlinear candidate could only add its equivalent linear part, which
the calibrated base and the linear candidates hold: it is not fitted
(`NonlinearityEvidence.text` says why, with the numbers). The screen errs towards
fitting: a false alarm costs time, never a finding. Measured (README campaigns, the
benchmark's and the independent truth's, 1 % noise): a model missing a linear effect (the
table's pitch) z 2.7-9.1, missing from a random run to an earthquake's (their spectra
differ: the estimator's bias differs); missing friction, orifice flow, a rated flow,
entrained air (4 %) or amplitude-dependent damping, z 20-166. Noise-free runs give the
estimates almost no scatter, and the estimator's own bias between runs of different
command spectra (random against an earthquake) reaches z 31 on an exact model: there the
nonlinear candidates are fitted; a floor at the reduced model's resolution would hide
entrained air, whose amplitude dependence is of that size.

A model that is nonlinear itself (friction added in an earlier round) makes a missing
linear effect's residual depend on amplitude too: the README's friction campaign, with
friction in and the force-feedback filter missing, reads z 31.5 there, and 1.9 once the
filter is in. So on such a model the nonlinear candidates are held back while the linear
ones are fitted (unless the best screen of the round before was a nonlinear one), and
fitted unless a linear candidate refined in its screen's task and passing the selection
(the lowest training cost of those) leaves no amplitude dependence (`linear_explains`, the
same statistic on its predictions); then they are not fitted, the reason with both
readings. Meanwhile they run only on cores the linear fits leave idle, after the
refinements started there, and are dropped if not needed.

The residual's power incoherent with the command (distortion) is not used: on a model
still missing a resonant linear effect the residual is sharp, and its coherence is biased
at every resolution a few-second run allows (`vtable.diagnose.stationarity`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from vtable.diagnose.campaign import Campaign
from vtable.diagnose.groups import group_prediction, group_signal, run_groups
from vtable.diagnose.sampling import BANDS

#: Hz: the band the screen reads (the analysis bands', above the lowest lines)
BAND_HZ = (0.3, BANDS[-1][1])
#: Welch averages the shortest run must give (its frames set everyone's)
MIN_AVERAGES = 8
#: lines of half-overlapping Hann frames are not independent: each counts this many times
LINE_CORRELATION = 1.5
#: amplitude dependence: standard deviations of the statistic above its mean
Z_SCREEN = 12.0
#: runs whose commands' RMS differ by less than this factor are at one amplitude
AMPLITUDES = 1.2
#: a line is read where the command has at least this share of its peak power
COMMAND_SHARE = 1e-4
#: a run's halves are compared (`residual_change`) where the command is steady: at one
#: amplitude (`AMPLITUDES`) and with each analysis band holding this share of its power ...
BAND_SHARE = 0.01
#: ... within this factor in both halves (a random command's bands scatter by up to 1.5
#: between 15 s halves; a sweep's or an earthquake's differ by far more)
BAND_SPREAD = 2.0


@dataclass
class NonlinearityEvidence:
    """The screen's reading: the largest amplitude statistic z over the pairs of runs and
    channel groups (where), how many pairs were compared and whether the runs' amplitudes
    differ enough to tell; `present`: the nonlinear candidates are worth fitting."""

    amplitude: float = 0.0
    amplitude_at: str = ""
    pairs: int = 0
    spread: float = 1.0  # the largest ratio of two runs' command RMS
    why_not: str = ""  # what kept the screen from reading the runs

    @property
    def present(self) -> bool:
        return not self.read or self.amplitude > Z_SCREEN

    @property
    def read(self) -> bool:
        """Whether the runs were compared at different amplitudes (else `present`)."""
        return not self.why_not and self.spread >= AMPLITUDES

    def text(self) -> str:
        """Why the nonlinear candidates are (not) fitted, with the numbers."""
        if self.why_not:
            return f"nonlinear candidates are fitted: {self.why_not}"
        if self.spread < AMPLITUDES:
            return ("nonlinear candidates are fitted: the runs' commands are all at one "
                    f"amplitude (RMS within x{self.spread:.2f}), so amplitude dependence "
                    "cannot be ruled out")
        stat = self._stat()
        if self.present:
            return f"amplitude dependence: nonlinear candidates are fitted ({stat})"
        return ("no amplitude dependence beyond the noise: a nonlinear candidate could "
                "only add its equivalent linear part, which the calibrated base holds; not "
                f"fitted ({stat})")

    def _stat(self) -> str:
        return (f"the residual's transfer function from the command differs between runs "
                f"of different amplitude (up to x{self.spread:.1f}) by at most "
                f"{self.amplitude:.1f} standard deviations of its estimates"
                + (f", {self.amplitude_at}" if self.amplitude_at else "")
                + f" (needs {Z_SCREEN:g})")

    def explained_text(self, linear: str, before: NonlinearityEvidence) -> str:
        """Why the nonlinear candidates are not fitted although the current model's
        residual (`before`) depends on amplitude: the fit of the linear candidate `linear`
        (refined, passing the selection), whose reading this is, leaves none."""
        return (f"the current model's residual depends on amplitude "
                f"({before.amplitude:.1f} standard deviations), but with {linear} fitted "
                "(refined this round, the selection's criteria met) no longer beyond the "
                "noise: a missing linear effect seen through the model's own nonlinearity; "
                "a nonlinear candidate could only add its equivalent linear part "
                f"(with {linear}: {self._stat()})")


def _frames(campaign: Campaign) -> int | None:
    """The Welch frame (samples) every run can average `MIN_AVERAGES` times, as fine as
    the shortest run allows; None when a run is too short for 64-sample frames."""
    n = min(len(r.time) for r in campaign.runs)
    nper = 1 << math.floor(math.log2(2 * n / (MIN_AVERAGES + 1)))
    return nper if nper >= 64 else None


def nonlinearity_evidence(campaign: Campaign,
                          predictions: dict[str, dict[str, np.ndarray]]
                          ) -> NonlinearityEvidence:
    """The screen (module docstring) on the current model's `predictions` of every run
    (analysis rate, whole runs)."""
    ev = NonlinearityEvidence()
    runs = campaign.runs
    if len(runs) < 2:
        ev.why_not = "one run: no amplitudes to compare"
        return ev
    nper = _frames(campaign)
    fs = runs[0].fs
    if nper is None or any(abs(r.fs - fs) > 1e-6 * fs for r in runs):
        ev.why_not = "the runs are too short or at different rates to compare"
        return ev
    rms = [float(np.std(r.channel("h_span"))) for r in runs]
    ev.spread = max(rms) / min(rms) if min(rms) > 0 else math.inf
    est: dict[str, dict[str, tuple]] = {}
    for run in runs:
        pred = predictions.get(run.name)
        if pred is None:
            ev.why_not = f"{run.name} has no prediction"
            return ev
        est[run.name] = _estimates(run, pred, slice(None), nper, fs)
    for (a, ea), (b, eb) in itertools.combinations(est.items(), 2):
        for g in ea.keys() & eb.keys():
            z = _z(ea[g], eb[g])
            if z is None:
                continue
            ev.pairs += 1
            if z > ev.amplitude:
                ev.amplitude, ev.amplitude_at = z, f"{a} against {b}, {g}"
    if not ev.pairs:
        ev.why_not = "no channel group to compare between runs"
    return ev


def linear_explains(campaign: Campaign, screen: NonlinearityEvidence,
                    fits: list[tuple[float, str, object]]) -> str:
    """Why a round's nonlinear candidates need no fit although the current model's residual
    (the model nonlinear itself) depends on amplitude (`screen`): of `fits` (training cost,
    effect, predictions of the whole runs: the round's linear candidates refined and
    admissible), the one with the lowest cost (then name) leaves no amplitude dependence;
    else '' (none, or it still does)."""
    fits = [f for f in fits if np.isfinite(f[0]) and isinstance(f[2], dict)]
    if not fits:
        return ""
    _, name, pred = min(fits, key=lambda f: (f[0], f[1]))
    after = nonlinearity_evidence(campaign, pred)
    return "" if after.present else after.explained_text(name, screen)


def _estimates(run, pred: dict[str, np.ndarray], part: slice, nper: int, fs: float
               ) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per channel group of `run`, on the samples `part` at the rate `fs` (one for every
    estimate compared: their lines are matched exactly): the lines read (`BAND_HZ`, where
    the command has power), the residual's H1 R from the command and its variance."""
    x = run.channel("h_span")[part]
    f, s_xx = scipy.signal.welch(x, fs, nperseg=nper)
    band = (f >= BAND_HZ[0]) & (f <= min(BAND_HZ[1], 0.45 * fs)) & \
        (s_xx > COMMAND_SHARE * s_xx.max())
    n_d = (len(x) - nper) // (nper // 2) + 1
    res = {}
    for g in run_groups(run):
        y, yh = group_signal(run, g), group_prediction(pred, run, g)
        if y is None or yh is None or not np.all(np.isfinite(yh[part])):
            continue
        res[g] = y[part] - yh[part]
    if not res:
        return {}
    # every group's residual in one call (scipy's cost is mostly per call)
    R = np.array(list(res.values()))
    _, S_rr = scipy.signal.welch(R, fs, nperseg=nper)
    _, S_xr = scipy.signal.csd(x, R, fs, nperseg=nper)
    out = {}
    for g, s_rr, s_xr in zip(res, S_rr, S_xr, strict=True):
        k = band & (s_rr > 0)
        if k.sum() < 4:
            continue
        coh = np.abs(s_xr[k]) ** 2 / (s_xx[k] * s_rr[k])
        out[g] = (f[k], s_xr[k] / s_xx[k], (1 - coh) * s_rr[k] / (n_d * s_xx[k]))
    return out


def _z(ea: tuple, eb: tuple) -> float | None:
    """How far two estimates of the residual's H1 differ: z = (χ² − L) / √(c L) over the
    lines both read (the module docstring); None on fewer than four lines."""
    (fa, ra, va), (fb, rb, vb) = ea, eb
    _, ia, ib = np.intersect1d(fa, fb, return_indices=True)
    v = va[ia] + vb[ib]
    ok = v > 0
    lines = int(ok.sum())
    if lines < 4:
        return None
    chi = float(np.sum(np.abs(ra[ia][ok] - rb[ib][ok]) ** 2 / v[ok]))
    return (chi - lines) / math.sqrt(LINE_CORRELATION * lines)


@dataclass
class ChangeEvidence:
    """Whether a run's residual changes between its halves: the largest statistic z (as
    the amplitude screen's) over the runs whose command is steady (`_steady`: else a
    nonlinearity's amplitude dependence, or the estimator's bias between different
    spectra, would read as a change)
    and their channel groups, where, and how many runs were compared."""

    change: float = 0.0
    change_at: str = ""
    runs: int = 0

    @property
    def present(self) -> bool:
        return self.change > Z_SCREEN

    def text(self) -> str:
        if not self.runs:
            return ("no run has a steady command and a prediction long enough to compare "
                    "its halves")
        return (f"the time-invariant model's residual, as a transfer function from the "
                f"command, differs between the halves of a run by at most {self.change:.1f} "
                f"standard deviations of its estimates" +
                (f" ({self.change_at})" if self.change_at else "") + f" (needs {Z_SCREEN:g})")


def residual_change(campaign: Campaign, predictions: dict[str, dict[str, np.ndarray]]
                    ) -> ChangeEvidence:
    """The residual's H1 from the command on the first half of each run against its second
    half (`ChangeEvidence`), on `predictions` (whole runs) of a time-invariant model: a
    specimen that changes during the run changes it; the noise alone leaves z near 0 (3-4
    measured on the truth's steady random runs)."""
    ev = ChangeEvidence()
    for run in campaign.runs:
        pred = predictions.get(run.name)
        x = run.channel("h_span")
        h = len(x) // 2
        if pred is None or 2 * h / (MIN_AVERAGES + 1) < 64 or not _steady(x, h, run.fs):
            continue
        nper = 1 << math.floor(math.log2(2 * h / (MIN_AVERAGES + 1)))
        first = _estimates(run, pred, slice(0, h), nper, run.fs)
        last = _estimates(run, pred, slice(h, 2 * h), nper, run.fs)
        zs = [(z, g) for g in first.keys() & last.keys()
              if (z := _z(first[g], last[g])) is not None]
        ev.runs += bool(zs)
        for z, g in zs:
            if z > ev.change:
                ev.change, ev.change_at = z, f"{run.name}, {g}"
    return ev


def _steady(x: np.ndarray, h: int, fs: float) -> bool:
    """Whether the command `x`'s two halves (`h` samples each) are at one amplitude (RMS
    within `AMPLITUDES`) with one spectrum (the power of each analysis band holding
    `BAND_SHARE` of the whole within `BAND_SPREAD`)."""
    p = []
    for part in (x[:h], x[h:2 * h]):
        f, s = scipy.signal.welch(part, fs, nperseg=min(len(part), 256))
        p.append(np.array([float(np.sum(s[(f >= lo) & (f < hi)])) for lo, hi in BANDS]))
    a, b = p
    if not min(a.sum(), b.sum()) > 0 or max(a.sum(), b.sum()) > AMPLITUDES ** 2 * min(
            a.sum(), b.sum()):
        return False
    used = (a > BAND_SHARE * a.sum()) | (b > BAND_SHARE * b.sum())
    return bool(np.all(np.maximum(a, b)[used] <= BAND_SPREAD * np.minimum(a, b)[used]))
