"""What a time-invariant model of the command could still fit, and what none can.

Every model vtable fits is driven by the command x_c (h_span). Of a model's residual
r = y − ŷ on a channel group y, the part coherent with the command, γ²_cr S_rr, is what a
better linear time-invariant model could still remove (the residual's H1 from the
command, Bendat & Piersol, *Random Data*, §9.2.2); the rest,

    U_r(f) = (1 − γ²_cr(f)) S_rr(f),     e_inc = sqrt(∫ U_r df / ∫ S_yy df),

no time-invariant model can: sensor noise, nonlinearity, change during the run. Because ŷ
is itself a time-invariant function of x_c, U_r is y's own incoherent power; computed on
the residual, where the model has taken out the sharp peak and notch, the spectral
resolution biases it far less than on y (on a 3 %-damped specimen at 0.1 Hz lines, y's own
coherence would put a 6.9 % "bound" on an exactly linear table). A model whose residual
is itself sharp (a mode a few % off) still biases it: the split is kept only where it is
stable when the resolution is halved (`STABLE`).

A change during the run is read from x_t/x_c on the first and last third of the run: its
notches (where x_t and x_c are coherent around them) hold the specimen's fixed-base
frequency (the zero of eq 7.9's numerator), so a notch that moves by more than a few
spectral lines means the specimen's stiffness changed during the run (softening: damage,
or a response that depends on the amplitude it has seen).

The spectra are Welch averages with Hann windows at `RESOLUTION_HZ` (at least
`MIN_AVERAGES` of them, `NOTCH_AVERAGES` in a third); shorter records are not judged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from vtable.diagnose.groups import group_prediction, group_signal, run_groups
from vtable.diagnose.sampling import BANDS, segments
from vtable.ident import frames
from vtable.runs.model import Run

#: the spectral resolution (Hz) of the coherence and of the notch search
RESOLUTION_HZ = 0.1
#: Welch averages at least, on the held-out segment and on each third of the run (notch)
MIN_AVERAGES = 8
NOTCH_AVERAGES = 4
#: the incoherent part is said only where halving the resolution raises it by at most this
#: factor: where it rises more, it is the resolution's bias (a residual with a sharp
#: spectrum: a model's mode a few % off), not the data's
STABLE = 1.15
#: a notch is a dip of x_t/x_c at least this deep against its surroundings (6 dB)
NOTCH_PROMINENCE = math.log(2.0)
#: a notch that moves by at least this many lines between the first and last third moved
NOTCH_LINES = 1.5
#: a notch counts where x_t and x_c are coherent around it (the median over ±1 Hz) ...
NOTCH_COHERENCE = 0.8
COHERENT_SPAN_HZ = 1.0
#: the notch is looked for in the analysis bands, from this frequency (Hz) up to their top
LOWEST_HZ = 0.5
#: ... and below this fraction of the command's band top, when the run declares it (the
#: band's edge makes a dip of x_t/x_c that is the command's, not the specimen's)
EDGE = 0.9


@dataclass(frozen=True)
class StationarityCheck:
    """One run: `splits` holds (group, coherent, incoherent) — the model's held-out
    residual split by its coherence with the command, each relative to the group's
    measured RMS; incoherent is None where the split is resolution-limited (`STABLE`),
    when a model was given; `notch` (first-third Hz, last-third Hz, the window in s) of
    x_t/x_c's notch that moved, else None."""

    run: str
    splits: tuple[tuple[str, float, float | None], ...] = ()
    notch: tuple[float, float, float] | None = None

    def text(self, floor: float, factor: float) -> str:
        """One line for the notes and the verdict: the groups whose residual holds more
        than `factor` x `floor` coherent with the command (what a time-invariant model
        could still fit there: at least that much, as the resolution moves coherent power
        to the incoherent side), or incoherent (what none can, where stable), and a moved
        notch; '' when none."""
        parts = []
        coh = [(g, c) for g, c, _ in self.splits if c > factor * floor]
        if coh:
            each = ", ".join(f"{g} {c:.1%}" for g, c in coh)
            parts.append(f"of the final model's held-out residual, at least {each} of the "
                         "signal is coherent with the command: a time-invariant model could "
                         "still fit it on that segment (the model fitted to the first 60 % "
                         "does not: a missing linear effect, or a change during the run)")
        inc = [(g, i) for g, _, i in self.splits if i is not None and i > factor * floor]
        if inc:
            each = ", ".join(f"{g} {i:.1%} ({i / floor:.1f} x the floor)" for g, i in inc)
            parts.append(f"no time-invariant model driven by the command can fit {each}: "
                         "incoherent with it (nonlinearity or change within the segment, "
                         "beyond the sensor noise)")
        if self.notch is not None:
            f1, f2, w = self.notch
            parts.append(f"x_t/x_c's notch (the specimen's fixed-base frequency) moves from "
                         f"{f1:.2f} Hz in the first {w:.0f} s to {f2:.2f} Hz in the last "
                         f"{w:.0f} s ({f2 / f1 - 1:+.0%}; stiffness {(f2 / f1) ** 2 - 1:+.0%}):"
                         " the specimen's stiffness changes during the run (softening: damage,"
                         " or a hysteretic specimen), which no time-invariant model follows")
        return f"{self.run}: " + "; ".join(parts) if parts else ""


def _nperseg(n: int, fs: float, averages: int) -> int | None:
    """Frames of `RESOLUTION_HZ` or finer with at least `averages` half-overlapping
    frames in `n` samples (`vtable.ident.frames.averages`), or None."""
    nper = 1 << math.ceil(math.log2(fs / RESOLUTION_HZ))
    return nper if frames.averages(n, nper) >= averages else None


class CoherentSplit:
    """The split of a residual by its coherence with one command `x` (module docstring),
    the command's spectrum taken once at `nperseg` and half of it, for every residual split
    against it: of a residual r over a measured y, the RMS of r's parts coherent
    (|S_xr|²/S_xx) and incoherent (S_rr − |S_xr|²/S_xx) with x, over y's RMS."""

    def __init__(self, x: np.ndarray, fs: float, nperseg: int) -> None:
        self.x, self.fs, self.nperseg = x, fs, nperseg
        self._sxx: dict[int, np.ndarray] = {}

    def at(self, r: np.ndarray, y: np.ndarray, n: int) -> tuple[float, float]:
        """(coherent, incoherent) on `n`-sample frames."""
        return self.at_many(np.array([r]), np.array([y]), n)[0]

    def at_many(self, R: np.ndarray, Y: np.ndarray, n: int) -> list[tuple[float, float]]:
        """`at` of each row of the residuals `R` over the measured `Y` (rows matched), the
        spectra of all in one scipy call each (its cost is mostly per call)."""
        if n not in self._sxx:
            self._sxx[n] = scipy.signal.welch(self.x, self.fs, nperseg=n)[1]
        f, S = scipy.signal.welch(np.concatenate([R, Y]), self.fs, nperseg=n)
        _, S_xr = scipy.signal.csd(self.x, R, self.fs, nperseg=n)
        s_xx, out = self._sxx[n], []
        for s_rr, s_yy, s_xr in zip(S[:len(R)], S[len(R):], S_xr, strict=True):
            k = (f > 0) & (s_xx > 0) & (s_rr > 0)
            total = float(np.sum(s_yy[f > 0]))
            if total <= 0:
                out.append((0.0, 0.0))
                continue
            coh = np.minimum(np.abs(s_xr[k]) ** 2 / (s_xx[k] * s_rr[k]), 1.0)
            out.append((float(np.sqrt(np.sum(coh * s_rr[k]) / total)),
                        float(np.sqrt(np.sum((1 - coh) * s_rr[k]) / total))))
        return out

    def stable(self, r: np.ndarray, y: np.ndarray) -> tuple[float, float | None]:
        """`at` on `nperseg`-sample frames, the incoherent part None when halving the
        resolution raises it by more than `STABLE` (resolution-limited)."""
        return self.stable_many(np.array([r]), np.array([y]))[0]

    def stable_many(self, R: np.ndarray, Y: np.ndarray) -> list[tuple[float, float | None]]:
        """`stable` of each row of `R` over `Y` (`at_many`)."""
        fine = self.at_many(R, Y, self.nperseg)
        coarse = self.at_many(R, Y, self.nperseg // 2)
        return [a if b[1] <= STABLE * a[1] else (a[0], None)
                for a, b in zip(fine, coarse, strict=True)]


def coherent_split(x: np.ndarray, r: np.ndarray, y: np.ndarray, fs: float,
                   nperseg: int) -> tuple[float, float]:
    """(coherent, incoherent): the RMS of the residual `r`'s parts coherent and incoherent
    with the command `x`, each over the RMS of the measured `y` (module docstring)."""
    return CoherentSplit(x, fs, nperseg).at(r, y, nperseg)


def stable_split(x: np.ndarray, r: np.ndarray, y: np.ndarray, fs: float,
                 nperseg: int) -> tuple[float, float | None]:
    """`coherent_split` at `nperseg`, its incoherent part None when halving the
    resolution raises it by more than `STABLE` (resolution-limited)."""
    return CoherentSplit(x, fs, nperseg).stable(r, y)


def notches(x: np.ndarray, y: np.ndarray, fs: float, nperseg: int,
            coherent: np.ndarray | None = None,
            prominence: float = NOTCH_PROMINENCE) -> list[tuple[float, float]]:
    """The dips of |H1(y/x)| at least `prominence` (`NOTCH_PROMINENCE`) deep in log |H|, between
    `LOWEST_HZ` and the analysis bands' top (30 Hz): (frequency Hz, interpolated between
    lines on a parabola through log |H|; prominence). With `coherent` (a boolean per
    line of these frames), only dips whose surroundings are coherent."""
    f, s_xy = scipy.signal.csd(x, y, fs, nperseg=nperseg)
    _, s_xx = scipy.signal.welch(x, fs, nperseg=nperseg)
    k = np.flatnonzero((f >= LOWEST_HZ) & (f <= min(BANDS[-1][1], 0.4 * fs)) & (s_xx > 0))
    if len(k) < 5:
        return []
    log_h = np.log(np.abs(s_xy[k]) / s_xx[k] + 1e-300)
    idx, props = scipy.signal.find_peaks(-log_h, prominence=prominence)
    df = f[1] - f[0]
    out = []
    for i, prom in zip(idx, props["prominences"], strict=True):
        if coherent is not None and not coherent[k[i]]:
            continue
        a, b, c = log_h[i - 1], log_h[i], log_h[i + 1]  # find_peaks keeps the ends out
        curv = a - 2 * b + c
        shift = 0.5 * (a - c) / curv if curv > 0 else 0.0
        out.append((float(f[k[i]] + shift * df), float(prom)))
    return out


def moved_notch(x: np.ndarray, y: np.ndarray, fs: float, top: float | None = None
                ) -> tuple[float, float, float] | None:
    """x_t/x_c's most prominent notch (in coherent surroundings, below `top` Hz when
    given) that moves down by `NOTCH_LINES` lines or more between the first and the last
    third of the run (the specimen softening): (first Hz, last Hz, the window in s), or
    None."""
    third = len(x) // 3
    n3 = _nperseg(third, fs, NOTCH_AVERAGES)
    if n3 is None:
        return None
    f, coh = scipy.signal.coherence(x, y, fs, nperseg=n3)
    half = max(1, round(COHERENT_SPAN_HZ / (f[1] - f[0])))
    around = np.array([np.median(coh[max(0, i - half):i + half + 1]) for i in range(len(f))])
    ok = (around >= NOTCH_COHERENCE) & (f < (top if top is not None else np.inf))
    ends = (x[:third], y[:third]), (x[-third:], y[-third:])
    deep = [notches(a, b, fs, n3, ok) for a, b in ends]
    # a notch that moves within a third is smeared there: the other third's may be half
    # as deep
    shallow = [notches(a, b, fs, n3, ok, NOTCH_PROMINENCE / 2) for a, b in ends]
    lines = fs / n3
    pairs = [(f1, p, shallow[1]) for f1, p in deep[0]] + \
        [(f2, p, shallow[0]) for f2, p in deep[1]]
    for f, _, other in sorted(pairs, key=lambda n: -n[1]):
        near = [g for g, _ in other if abs(g / f - 1) < 0.15]
        if near:
            g = min(near, key=lambda v: abs(v - f))
            f1, f2 = (f, g) if other is shallow[1] else (g, f)
            if f1 - f2 >= NOTCH_LINES * lines:
                return f1, f2, third / fs
    return None


def stationarity_check(run: Run, predictions: dict[str, np.ndarray] | None = None
                       ) -> StationarityCheck | None:
    """What a time-invariant model of `run`'s command could still fit, and what none can.

    Parameters
    ----------
    run
        A run at the analysis rate with the command h_span.
    predictions
        A model's predicted channels for the run (the diagnosis's final stage); without
        them only the notch is read.

    Returns
    -------
    StationarityCheck or None
        The residual's split per channel group on the held-out segment (with
        `predictions`, when it is long enough for `MIN_AVERAGES` frames), and x_t/x_c's
        notch when it moved by `NOTCH_LINES` lines or more; None when the run has no
        command or it is constant.
    """
    if not run.has("h_span") or float(np.std(run.channel("h_span"))) == 0:
        return None
    x, fs = run.channel("h_span"), run.fs
    splits = []
    held = segments(run)[1]
    nper = _nperseg(len(x[held]), fs, MIN_AVERAGES)
    if predictions is not None and nper is not None:
        for g in run_groups(run):
            y, yh = group_signal(run, g), group_prediction(predictions, run, g)
            if y is not None and yh is not None:
                y, yh = y[held], yh[held]
                splits.append((g, *stable_split(x[held], y - yh, y, fs, nper)))
    y = group_signal(run, "table displacement")
    drive = run.drive()
    top = EDGE * drive.band[1] if drive is not None and drive.band and drive.band[1] > 0 \
        else None
    notch = None if y is None else moved_notch(x, y, fs, top)
    return StationarityCheck(run.name, tuple(splits), notch)
