"""Frame lengths for transfer-function estimates: enough averages, enough resolution.

An H1 estimate (eqs 3.1-3.2, Hann window, 50 % overlap) of N samples in frames of n has
resolution Δf = fs/n and n_d = 1 + ⌊(N - n)/(n/2)⌋ averages. Two errors compete:

- random error: the normalised random error of |H| is about √(1 - γ²)/(|γ|√(2 n_d))
  (Bendat & Piersol); with γ² = 0.9 it is 8 % at n_d = 8, and with n_d = 1 the
  coherence is 1 by construction. Rule: ``n_d >= MIN_AVERAGES`` (8).
- resolution bias: a spectral peak of half-power band B_r = 2ξf seen through the Hann
  window's effective bandwidth B_e ≈ 1.5 Δf is lowered by about (B_e/B_r)²/3, and the
  damping read from it raised as much. Rule: the band holds ``LINES_PER_BAND`` (3) lines,
  Δf <= 2ξf/3, which keeps that bias near 8 %.

`frame_for_mode` picks, for a mode (f, ξ), the shortest power-of-two frame satisfying
both (the most averages among the resolving frames). When none does, it takes the
longest frame still giving 8 averages, then (a short record) one giving at least
``FEWEST_AVERAGES`` (2), as long as the fitting band (± ``FIT_HALF_WIDTH`` of f) holds
``FIT_LINES`` lines; the fit is then made and its damping flagged unresolved (or its
averages too few) by `vtable.ident.validity`. When no frame can hold the fit, it says so
with the record length the rule needs.
"""

from __future__ import annotations

from dataclasses import dataclass

from vtable.errors import VtableError

MIN_AVERAGES = 8
LINES_PER_BAND = 3
FEWEST_AVERAGES = 2
FIT_LINES = 4
FIT_HALF_WIDTH = 0.15
SHORTEST = 64
OVERLAP = 0.5


def averages(n_samples: int, nperseg: int, overlap: float = OVERLAP) -> int:
    """Number of frames of `nperseg` in `n_samples` at `overlap` (0 if it does not fit)."""
    if n_samples < nperseg:
        return 0
    step = nperseg - round(overlap * nperseg)
    return 1 + (n_samples - nperseg) // step


def _powers(n_samples: int) -> list[int]:
    out, n = [], SHORTEST
    while n <= n_samples:
        out.append(n)
        n *= 2
    return out


def frame_for_averages(n_samples: int, min_averages: int = MIN_AVERAGES,
                       longest: int | None = None) -> int | None:
    """The longest power-of-two frame (>= 64, <= `longest`) giving at least
    `min_averages` averages at 50 % overlap; None when even 64 points do not."""
    ok = [n for n in _powers(n_samples) if averages(n_samples, n) >= min_averages
          and (longest is None or n <= longest)]
    return max(ok) if ok else None


def record_needed(fs: float, f_n: float, xi_n: float) -> float:
    """Seconds of record the rule needs for the mode: 8 averages of the shortest
    power-of-two frame with 3 lines in its half-power band."""
    n = SHORTEST
    while fs / n > 2 * xi_n * f_n / LINES_PER_BAND:
        n *= 2
    return (n + (MIN_AVERAGES - 1) * (n - round(OVERLAP * n))) / fs


@dataclass(frozen=True)
class FrameChoice:
    """A frame length for one mode and why."""

    nperseg: int
    fs: float
    averages: int
    f_n: float
    xi_n: float
    resolved: bool
    enough_averages: bool
    why: str

    @property
    def resolution_hz(self) -> float:
        return self.fs / self.nperseg

    @property
    def lines(self) -> float:
        """Lines of the estimate inside the half-power band 2ξf."""
        return 2 * self.xi_n * self.f_n / self.resolution_hz


def frame_for_mode(n_samples: int, fs: float, f_n: float, xi_n: float,
                   what: str = "the mode") -> FrameChoice:
    """The frame for fitting a mode near `f_n` with damping about `xi_n` (the rule of
    the module docstring). Raises VtableError, with the record the rule needs, when the
    record cannot hold a fit at all."""
    if not (f_n > 0 and xi_n > 0):
        raise VtableError(f"{what}: need a positive frequency and damping to choose frames, "
                          f"got {f_n:g} Hz, {xi_n:g}")
    band = 2 * xi_n * f_n

    def choice(n: int, why: str) -> FrameChoice:
        nd = averages(n_samples, n)
        return FrameChoice(n, fs, nd, f_n, xi_n, fs / n <= band / LINES_PER_BAND,
                           nd >= MIN_AVERAGES, why)

    cands = _powers(n_samples)
    good = [n for n in cands if fs / n <= band / LINES_PER_BAND
            and averages(n_samples, n) >= MIN_AVERAGES]
    if good:
        return choice(min(good), f"resolves the half-power band ({LINES_PER_BAND}+ lines) "
                                 f"with {MIN_AVERAGES}+ averages")
    fits = [n for n in cands if 2 * FIT_HALF_WIDTH * f_n / (fs / n) >= FIT_LINES]
    avg8 = [n for n in fits if averages(n_samples, n) >= MIN_AVERAGES]
    need = record_needed(fs, f_n, xi_n)
    short = (f"resolving the half-power band of the mode it was chosen for ({f_n:.3g} Hz, "
             f"ξ {xi_n:.3g}: 2ξf = {band:.3g} Hz) with {MIN_AVERAGES} averages needs "
             f"≥ {need:.0f} s")
    if avg8:
        return choice(max(avg8), f"the finest frame with {MIN_AVERAGES} averages; {short}")
    few = [n for n in fits if averages(n_samples, n) >= FEWEST_AVERAGES]
    if few:
        return choice(min(few), f"the only frames that hold the fit give few averages; "
                                f"{short}")
    best = fs / max(cands) if cands else float("inf")
    raise VtableError(
        f"{what}: a fit near {f_n:.3g} Hz needs {FIT_LINES} lines within ±"
        f"{100 * FIT_HALF_WIDTH:.0f} % with ≥ {FEWEST_AVERAGES} averages; "
        f"{n_samples / fs:.1f} s at {fs:.0f} Hz resolves at best {best:.3g} Hz with 1 "
        f"average ({short})")
