"""The statistics of a comparison: the normalised RMS error, the errors of one model on a
campaign (`Comparison`) and the held-out gain of one model over another with the standard
error the sensor noise alone gives it (`Gain`, what the selection rule tests)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from vtable.diagnose.groups import group_prediction, group_signal, run_groups
from vtable.diagnose.sampling import segments
from vtable.runs.model import Run


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
    display: str = "imperial"  # the runs' unit family (`vtable.display.family`)

    def worst_groups(self, k: int = 2) -> list[tuple[str, float]]:
        agg: dict[str, list[float]] = {}
        for errs in self.per_run.values():
            for g, e in errs.items():
                agg.setdefault(g, []).append(e)
        return sorted(((g, float(np.mean(v))) for g, v in agg.items()), key=lambda x: -x[1])[:k]

    def worst_band(self, group: str) -> tuple[str, float] | None:
        b = self.bands.get(group)
        return max(b.items(), key=lambda x: x[1]) if b else None


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
    def z_text(self) -> str:
        """`z` in words: '4.7 standard errors of the noise'; beyond ±`Z_SAID` the runs are
        nearly noise-free and the figure means nothing a reader could check, so it says so
        (the selection rule's resolution criterion decides there)."""
        return standard_errors(self.z)

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


#: |z| beyond which `standard_errors` no longer prints the figure
Z_SAID = 1e6


def standard_errors(z: float) -> str:
    """A z statistic in words (`Gain.z_text`)."""
    if abs(z) <= Z_SAID:
        return f"{z:.1f} standard errors of the noise"
    return (f"{'more' if z > 0 else 'less'} than {'+' if z > 0 else '-'}10^6 standard errors "
            "of the noise (the runs are nearly noise-free: the model's resolution decides)")


def correlations(jac: np.ndarray, n: int) -> np.ndarray:
    """Correlation matrix of the fitted parameters (Gauss-Newton: cov ∝ (JᵀJ)⁻¹); a
    parameter the residual does not depend on gets NaN on its diagonal."""
    J = np.asarray(jac, dtype=float)
    JtJ = J.T @ J
    d = np.sqrt(np.diag(JtJ))
    R = np.full((n, n), np.nan)
    ok = d > 1e-12 * max(float(d.max()) if d.size else 0.0, 1e-300)
    if not ok.any():
        return R
    cov = np.linalg.pinv(JtJ[np.ix_(ok, ok)] / np.outer(d[ok], d[ok]))
    s = np.sqrt(np.abs(np.diag(cov)))
    sub = cov / np.outer(s, s)
    R[np.ix_(ok, ok)] = sub
    return R
