"""Whether a campaign's runs hold one plant (issue 32, deliverable 3): x_t/x_c of two runs
compared beyond what the fitted model itself predicts for them.

Every run's x_t/x_c is estimated by H1 (`ident.tf.transfer_function`) from the measured
table displacement and from the final model's prediction of it. The model's own difference
between two runs (a nonlinear effect in it: friction at two amplitudes) is removed, and
what is left,

    d(f) = (H_i − Ĥ_i) − (H_j − Ĥ_j),

is compared with the estimates' random error, the variance of the complex H1 being
σ_H² = |H|² (1 − γ²) / (γ² n_d) for each run (twice the variance of its gain, Bendat &
Piersol, *Random Data*, eq 9.90; n_d averages, γ² the coherence). On the
lines where both runs are coherent (γ² ≥ `COHERENCE`) within `BAND_HZ`, z = |d| / √(σ_i² +
σ_j²). Where the runs hold one plant z² is exponentially distributed with mean 1 (d a complex
Gaussian of variance σ_i² + σ_j²), so its mean over n lines is 1 ± 1/√n; two runs whose mean
z² exceeds 1 + `SIGMAS`/√n do not hold one plant the model describes: a specimen that
changed between them, or an amplitude dependence no effect in the model follows.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from vtable.diagnose.groups import group_prediction, group_signal
from vtable.ident import frames
from vtable.ident.tf import transfer_function
from vtable.runs.model import Run

#: frame length (samples at the analysis rate: 0.39 Hz lines at 200 Hz) at least; a pair of
#: longer runs is compared on the longest frame that gives both `AVERAGES` averages (a
#: specimen 4 % softer moves a 3 Hz notch by a third of a 512-point line)
FRAME = 512
AVERAGES = 16
#: the lines compared: both runs this coherent, within this band (Hz)
COHERENCE = 0.9
BAND_HZ = (0.5, 20.0)
#: lines at least, and the standard deviations of the mean of z² beyond its 1 at which two
#: runs differ
MIN_LINES = 5
SIGMAS = 4.0


@dataclass(frozen=True)
class PlantDifference:
    """Two runs whose x_t/x_c differ beyond their estimates' confidence and beyond the
    model's own difference: the mean z² and the largest z over `lines` lines, and where (Hz)
    and by how much (relative to |H|) the largest unexplained difference is."""

    runs: tuple[str, str]
    z2_mean: float
    z_max: float
    lines: int
    at_hz: float
    relative: float

    def text(self) -> str:
        a, b = self.runs
        return (f"{a} and {b} do not hold one plant: their x_t/x_c differ by up to "
                f"{self.relative:.0%} at {self.at_hz:.1f} Hz beyond what the model predicts "
                f"for each (mean squared {self.z2_mean:.1f} x the estimates' own scatter over "
                f"{self.lines} coherent lines)")


def frame_for(n: int) -> int:
    """The frame two runs of at least `n` samples are compared on (`FRAME`, `AVERAGES`)."""
    return max(FRAME, frames.frame_for_averages(n, AVERAGES) or FRAME)


def _estimate(run: Run, predictions, nper: int):
    """(f, H measured, H predicted, σ_H, coherent lines) of the run's x_t/x_c on frames of
    `nper`, or None."""
    y = group_signal(run, "table displacement")
    y_hat = group_prediction(predictions, run, "table displacement") if predictions else None
    if y is None or y_hat is None or not run.has("h_span") or len(y) < 2 * nper:
        return None
    x = run.channel("h_span")
    m, p = transfer_function(x, y, run.fs, nper), transfer_function(x, y_hat, run.fs, nper)
    g = np.clip(m.coherence, 1e-12, 1.0)
    sigma = np.abs(m.H) * np.sqrt((1 - g) / (g * m.averages))
    ok = (m.coherence >= COHERENCE) & (m.f >= BAND_HZ[0]) & (m.f <= BAND_HZ[1]) & \
        np.isfinite(m.H) & np.isfinite(p.H)
    return m.f, m.H, p.H, sigma, ok


def plant_differences(runs: list[Run], predictions: dict[str, dict[str, np.ndarray]]
                      ) -> list[PlantDifference]:
    """The pairs of `runs` (at one analysis rate) that do not hold one plant the model
    with `predictions` ({run: channels}) describes (module docstring), largest first."""
    by_name = {r.name: r for r in runs}
    memo: dict[tuple[str, int], Any] = {}

    def estimate(name: str, nper: int):
        if (name, nper) not in memo:
            memo[name, nper] = _estimate(by_name[name], predictions.get(name), nper)
        return memo[name, nper]

    out = []
    for a, b in itertools.combinations(by_name, 2):
        nper = frame_for(min(len(by_name[a].time), len(by_name[b].time)))
        ea, eb = estimate(a, nper), estimate(b, nper)
        if ea is None or eb is None:
            continue
        fa, Ha, Pa, sa, oka = ea
        fb, Hb, Pb, sb, okb = eb
        if len(fa) != len(fb) or not np.allclose(fa, fb):
            continue
        k = oka & okb
        if k.sum() < MIN_LINES:
            continue
        d = (Ha - Pa) - (Hb - Pb)
        z = np.abs(d[k]) / np.sqrt(sa[k] ** 2 + sb[k] ** 2)
        zm = float(np.mean(z**2))
        if zm > 1 + SIGMAS / math.sqrt(len(z)):
            i = int(np.argmax(z))
            rel = float(np.abs(d[k][i]) / max(np.abs(Ha[k][i]), 1e-300))
            out.append(PlantDifference((a, b), zm, float(z[i]), int(k.sum()),
                                       float(fa[k][i]), rel))
    return sorted(out, key=lambda p: -p.z2_mean)
