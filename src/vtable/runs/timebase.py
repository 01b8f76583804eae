"""A run's time base: time stamps checked (increasing, uniform within the spec's
tolerance or within their printed precision) and put on the uniform grid t0 + k·dt."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from vtable.errors import VtableError

#: a time step is uniform when within this fraction of the median step (spec)
UNIFORM_TOL = 1e-3
#: time stamps closer than this fraction of a step to the fitted grid are kept as they are
#: (float rounding of a uniform grid); otherwise the grid t0 + k·dt replaces them
GRID_TOL = 1e-9


def check_time(t: np.ndarray, where: Path | str, first_line: int = 2,
               what: str = "line") -> tuple[np.ndarray, float]:
    """Check time stamps (s) and return the time base and the largest deviation of the
    stamps from it.

    Stamps must increase; a step counts as uniform within `UNIFORM_TOL` of the median
    step (relative, the spec's rule), or when the stamps' printed precision explains the
    scatter (`_rounded_grid`: 7 significant digits at t = 12.34567 s shift a 256 Hz step
    by 2.6e-3 of itself, and lab exports print so); a larger irregularity (a lost sample,
    a restart) is an error naming the line. The time base is the least-squares grid
    t0 + k·dt through the stamps, or the stamps themselves when they are that grid to
    `GRID_TOL` of a step (float rounding), so runs round-trip exactly.
    """
    def at(i: int) -> str:
        return f"{what} {i + first_line}"

    nan = np.flatnonzero(np.isnan(t))
    if len(nan):
        raise VtableError(f"{where}: {at(int(nan[0]))}: column 'time' has missing samples")
    steps = np.diff(t)
    back = np.flatnonzero(~(steps > 0))
    if len(back):
        i = int(back[0])
        how = "repeats" if steps[i] == 0 else "goes back from"
        raise VtableError(f"{where}: {at(i + 1)}: time {t[i + 1]:.9g} s {how} "
                          f"{t[i]:.9g} s ({at(i)}); time stamps must increase")
    med = float(np.median(steps))
    n = len(t)
    k = np.arange(n, dtype=float)
    kc = k - (n - 1) / 2
    t_mean = float(np.mean(t))
    dt = float(np.dot(kc, t - t_mean) / np.dot(kc, kc))
    grid = t_mean + kc * dt
    off = np.flatnonzero(np.abs(steps - med) > UNIFORM_TOL * med)
    if len(off) and not _rounded_grid(t, grid, dt):
        dev = np.abs(steps[off] - med)
        i = int(off[np.argmax(dev >= 0.5 * dev.max())])  # the first large irregularity
        raise VtableError(f"{where}: column 'time' is not uniform: step {steps[i]:.9g} s at "
                          f"{at(i + 1)} vs median {med:.9g} s (a lost sample or a restart?)")
    dev = float(np.max(np.abs(t - grid)))
    if dev <= GRID_TOL * dt:
        return t, dev
    return grid, dev


def _rounded_grid(t: np.ndarray, grid: np.ndarray, dt: float) -> bool:
    """Whether stamps whose steps scatter beyond the spec's tolerance are a uniform grid
    printed with limited precision: every stamp within its printing rounding
    (`printed_quantum`) of the least-squares grid, that rounding finer than a tenth of a
    step (so a lost sample, half a step off the grid, is never explained away)."""
    q = printed_quantum(t)
    if not q.any() or q.max() > 0.1 * dt:
        return False
    return bool(np.all(np.abs(t - grid) <= q + UNIFORM_TOL * dt))


def printed_quantum(t: np.ndarray, most: int = 17) -> np.ndarray:
    """Half-width of the rounding each stamp may carry from being printed: the file's
    significant digits S are the most any stamp needs (up to `most`); a stamp at t was
    then rounded to 10^(⌊log₁₀|t|⌋ − S + 1). Files printed with fewer than 6 significant
    digits are taken as exact (stamps like 0.005 need no more), full-precision files
    (S ≥ 15) too."""
    q = np.zeros(len(t))
    nz = t != 0
    if not nz.any():
        return q
    tz = np.abs(t[nz])
    mag = np.floor(np.log10(tz))
    sig = np.full(len(tz), most)
    left = np.ones(len(tz), dtype=bool)
    for d in range(1, most + 1):
        if not left.any():
            break
        unit = 10.0 ** (mag[left] - d + 1)
        x = tz[left] / unit
        hit = np.abs(x - np.round(x)) <= 1e-6 * np.maximum(x, 1.0) * 1e-3
        idx = np.flatnonzero(left)[hit]
        sig[idx] = d
        left[idx] = False
    digits = int(sig.max())
    if digits < 6 or digits >= 15:
        return q
    q[nz] = 0.5 * 10.0 ** (mag - digits + 1)
    return q

