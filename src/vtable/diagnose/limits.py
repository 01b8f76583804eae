"""What the data allow a model of the command, run by run and channel group: a black box's
held-out error (the reference) and the part of the held-out signal no time-invariant model
can fit (the bound), and a model's held-out error split into noise, *within reach* and
*beyond* (issue 32, deliverable 1).

The reference is a generic time-invariant predictor of each channel group y from the
command x_c, trained on the diagnosis's own training segment and scored as the model is
(NRMS on the held-out last 40 %): the H1 estimate H = S_xy / S_xx (Welch, Hann frames; Bendat
& Piersol, *Random Data*, §9.2.2), zero on the lines where the command has no power
(`QUIET`), turned into a two-sided FIR by its inverse FFT, centred, and convolved with the
whole command; the best of 256-, 512- and 1024-point frames (`FRAMES`). It is not a bound:
a physics model of the right form has far fewer unknowns and should do at least as well.

The bound is the part of y incoherent with the command on the held-out segment itself
(`stationarity.CoherentSplit`, the command's spectra taken once per run; on coarser
frames when the segment is short, `_frames`),
split on the model's residual: for a linear model ŷ is a time-invariant function of x_c,
so the incoherent part is y's own and no linear time-invariant model of the command can fit
it; the model has taken out the sharp peak and notch that bias the split at a finite
resolution (split on y itself, or on a black box's residual, a linear truth's 1 % noise
reads as 3-60 %). A nonlinear model takes part of y's incoherent power out: its bound is
what it leaves incoherent. Where the split is resolution-limited the group's sensor noise
stands for it (noise is incoherent with the command: still a lower bound). Of the model's
held-out error e, split on its residual,

    e² ≈ coherent² + incoherent²,   incoherent² ≈ noise² + beyond²,

the coherent part is *within reach* (a missing linear effect: a time-invariant model could
still fit it) and *beyond* is what is left of the incoherent part above the noise
(nonlinearity, a change during the run, disturbances). Campaign figures are the mean over
runs and channel groups, as the error is (`compare.compare`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from vtable.diagnose.groups import group_prediction, group_signal, run_groups
from vtable.diagnose.noise import group_noise
from vtable.diagnose.sampling import segments
from vtable.diagnose.stationarity import MIN_AVERAGES, CoherentSplit, _nperseg
from vtable.diagnose.statistics import nrms
from vtable.ident.frames import averages
from vtable.runs.model import Run

#: the black box's frame lengths (samples at the analysis rate); the best is kept
FRAMES = (256, 512, 1024)
#: a line of the command's spectrum this far below its peak has no power to estimate from
QUIET = 1e-6


#: the coarsest frame the split is made on (samples): a held-out part too short for the
#: stationarity check's resolution is split on the finest frames that still average
#: `MIN_AVERAGES` times, down to this
SHORTEST_FRAME = 128


def _frames(n: int, fs: float) -> int | None:
    """The split's frame length on a held-out part of `n` samples: the stationarity
    check's (`stationarity.RESOLUTION_HZ`) when it fits `MIN_AVERAGES` times, else the
    longest power of two that does, down to `SHORTEST_FRAME`; None below."""
    nper = _nperseg(n, fs, MIN_AVERAGES)
    if nper is not None:
        return nper
    nper = 1 << max(0, n.bit_length() - 1)
    while nper >= SHORTEST_FRAME and averages(n, nper) < MIN_AVERAGES:
        nper //= 2
    return nper if nper >= SHORTEST_FRAME else None


def black_box(x: np.ndarray, y: np.ndarray, train: slice, held: slice,
              frames: tuple[int, ...] = FRAMES, _sxx: dict | None = None
              ) -> tuple[float, int, np.ndarray] | None:
    """The reference predictor's held-out NRMS error, its frame length and its prediction
    of y: the H1 of y over x on `train` as a centred FIR, played on the whole command and
    scored on `held` (module docstring); None when the training segment is shorter than
    two of every frame. `_sxx`: the command's spectra by frame length, kept across a run's
    groups."""
    best = None
    cache = {} if _sxx is None else _sxx
    for n in frames:
        if train.stop - (train.start or 0) < 2 * n:
            continue
        _, s_xy = scipy.signal.csd(x[train], y[train], nperseg=n)
        if n not in cache:
            cache[n] = scipy.signal.welch(x[train], nperseg=n)[1]
        s_xx = cache[n]
        # lines where the command has no power (`QUIET` below its peak: beyond its band)
        # carry no estimate: there H1 is noise over nothing, and it is left out (zero)
        s_xx = np.where(s_xx > QUIET * np.max(s_xx), s_xx, np.inf)
        h = np.fft.irfft(s_xy / s_xx, n)
        y_hat = scipy.signal.fftconvolve(x, np.roll(h, n // 2))[n // 2:n // 2 + len(x)]
        e = nrms(y_hat[held], y[held])
        if best is None or e < best[0]:
            best = (e, n, y_hat)
    return best


@dataclass(frozen=True)
class GroupLimit:
    """One run's channel group, each figure relative to the group's held-out RMS: the
    black box's error (`reference`, None when the run is too short) and its frame, the
    part no time-invariant model can fit (`bound`; `resolved` False where the split was
    resolution-limited and the sensor noise stands for it), the noise, and, with a model,
    its error split into within reach and beyond (None where resolution-limited)."""

    run: str
    group: str
    reference: float | None
    frame: int | None
    bound: float
    resolved: bool
    noise: float
    error: float | None = None
    within_reach: float | None = None
    beyond: float | None = None

    def to_json(self) -> dict:
        return dict(self.__dict__)


@dataclass(frozen=True)
class Limits:
    """Every run's groups (`groups`) and the campaign's figures on the error's scale (the
    mean over runs and groups): `reference` (None when no run is long enough), `bound`,
    and the model's error split (`noise`, `within_reach`, `beyond`; None without a
    model)."""

    groups: tuple[GroupLimit, ...]

    def _mean(self, name: str) -> float | None:
        vals = [getattr(g, name) for g in self.groups]
        return None if not vals or any(v is None for v in vals) else float(np.mean(vals))

    @property
    def reference(self) -> float | None:
        vals = [g.reference for g in self.groups if g.reference is not None]
        return float(np.mean(vals)) if vals and len(vals) == len(self.groups) else None

    @property
    def bound(self) -> float | None:
        return self._mean("bound")

    @property
    def noise(self) -> float | None:
        return self._mean("noise")

    def _known(self, name: str) -> float | None:
        vals = [v for g in self.groups if (v := getattr(g, name)) is not None]
        return float(np.mean(vals)) if vals else None

    @property
    def within_reach(self) -> float | None:
        """The mean over the groups whose split was made."""
        return self._known("within_reach")

    @property
    def beyond(self) -> float | None:
        """The mean over the groups whose split was resolved."""
        return self._known("beyond")

    def by_run(self) -> dict[str, tuple[float, float]]:
        """Each run's model error and black box's error (the means over its groups), for
        the runs whose every group has both."""
        runs: dict[str, list[GroupLimit]] = {}
        for g in self.groups:
            runs.setdefault(g.run, []).append(g)
        return {run: (float(np.mean([g.error for g in gs])),
                      float(np.mean([g.reference for g in gs])))
                for run, gs in runs.items()
                if all(g.error is not None and g.reference is not None for g in gs)}

    def to_json(self) -> dict:
        return {"reference": self.reference, "bound": self.bound, "noise": self.noise,
                "within_reach": self.within_reach, "beyond": self.beyond,
                "frames": list(FRAMES), "groups": [g.to_json() for g in self.groups]}

    def text(self) -> str:
        """The per-run lines of the report (empty with no groups)."""
        out = []
        for g in self.groups:
            ref = _pct(g.reference)
            line = (f"  {g.run:<16} {g.group:<24} black box {ref:>7}, bound "
                    f"{g.bound:.2%}{'' if g.resolved else ' (noise)'}")
            if g.error is not None:
                line += (f"; model {g.error:.2%} = noise {g.noise:.2%}, within reach "
                         f"{_pct(g.within_reach)}, beyond {_pct(g.beyond)}")
            out.append(line)
        return "\n".join(out)


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{v:.2%}"


def limits(runs: list[Run], predictions: dict[str, dict[str, np.ndarray]] | None = None
           ) -> Limits:
    """What the data allow on `runs` (at the analysis rate), and, with a model's
    `predictions` ({run: channels}), how its held-out error splits (module docstring).
    Without predictions the bound is the sensor noise alone (unresolved)."""
    out = []
    for r in runs:
        if not r.has("h_span"):
            continue
        x = r.channel("h_span")
        train, held = segments(r)
        sigma = group_noise(r)
        nper = _frames(held.stop - held.start, r.fs)
        split = None if nper is None else CoherentSplit(x[held], r.fs, nper)
        sxx: dict = {}
        p = None if predictions is None else predictions.get(r.name)
        groups = []  # (group, measured, predicted or None)
        for g in run_groups(r):
            y = group_signal(r, g)
            if y is not None:
                groups.append((g, y, None if p is None else group_prediction(p, r, g)))
        # the model's residuals, coherent and incoherent, every group's in one call each
        fitted = [(y[held] - y_hat[held], y[held]) for _, y, y_hat in groups if y_hat is not None]
        splits = iter(split.stable_many(*map(np.array, zip(*fitted, strict=True)))
                      if split is not None and fitted else ())
        for g, y, y_hat in groups:
            rms = float(np.sqrt(np.mean(y[held] ** 2)))
            noise = min(sigma.get(g, 0.0) / rms, 1.0) if rms > 0 else 1.0
            ref = black_box(x, y, train, held, _sxx=sxx)
            inc = err = within = beyond = None
            if y_hat is not None:  # the model's residual: coherent, and incoherent
                err = nrms(y_hat[held], y[held])
                if split is not None:
                    within, inc = next(splits)
                    within = min(within, err)  # spectra and time series differ a little
                    if inc is not None:  # resolution-limited: not known (None)
                        beyond = math.sqrt(max(inc**2 - noise**2, 0.0))
            resolved = inc is not None
            bound = max(inc, noise) if resolved else noise
            out.append(GroupLimit(r.name, g, None if ref is None else ref[0],
                                  None if ref is None else ref[1], bound, resolved, noise,
                                  err, within, beyond))
    return Limits(tuple(out))
