"""The sensor noise of a campaign: each channel's σ (from redundant sensors, or the spectrum
above the response band), each group's, and the noise floor, the error the noise alone
would cost.

Whether a final error is "consistent with the noise floor" (`unexplained`): sensor noise
and a systematic model error are independent, so their squared NRMS add,
err² ≈ floor² + sys². The error is called consistent with the noise when
err ≤ NOISE_FACTOR × floor (2×), i.e. when the systematic part is at most √3 ≈ 1.7 times
the noise; above that a residual remains unexplained and is localised.
"""

from __future__ import annotations

import numpy as np
import scipy.signal

from vtable.diagnose.groups import group_signal, run_groups
from vtable.diagnose.sampling import segments
from vtable.runs.model import Run

NOISE_FACTOR = 2.0  # a final error <= 2 x the noise floor is consistent with the noise
UNEXPLAINED_RULE = (f"unexplained is null when the final error <= {NOISE_FACTOR:g} x the noise "
                    "floor: noise and a systematic error add in quadrature, err^2 = floor^2 + "
                    f"sys^2, so this admits a systematic part up to "
                    f"{np.sqrt(NOISE_FACTOR**2 - 1):.2f} x the noise; otherwise it gives the "
                    "ratio final error / noise floor and where the final model's residual "
                    "lives (worst channel group, its worst band, the amplitude trend, the worst "
                    "2 s window)")


def within_noise(error: float, floor: float) -> bool:
    """Whether a held-out `error` is consistent with the noise `floor` alone
    (`UNEXPLAINED_RULE`: at most `NOISE_FACTOR` x a positive floor)."""
    return floor > 0 and error <= NOISE_FACTOR * floor


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

