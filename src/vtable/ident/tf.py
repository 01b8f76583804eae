"""Transfer-function estimation between two channels (report §3.2, eqs 3.1-3.2).

H1 = G_xy/G_xx with coherence γ² = |G_xy|²/(G_xx G_yy), averaged over Hann-windowed,
overlapping frames (scipy.signal.csd / welch); 2048-point frames as in §3.2 unless told.
Which frame length a record allows (averages against resolution) is vtable.ident.frames'
job; with one frame the coherence is 1 by construction.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.signal

from vtable.errors import VtableError


@dataclass(frozen=True)
class TransferFunction:
    """An estimated frequency response with its coherence and the number of averages."""

    f: np.ndarray
    H: np.ndarray
    coherence: np.ndarray
    averages: int

    @property
    def resolution_hz(self) -> float:
        """Line spacing Δf = fs/nperseg."""
        return float(self.f[1] - self.f[0])

    def at(self, f_hz) -> np.ndarray:
        """Interpolated H at other frequencies (real and imaginary parts separately)."""
        return (np.interp(f_hz, self.f, self.H.real) + 1j * np.interp(f_hz, self.f, self.H.imag))


def welch_kw(fs: float, nperseg: int = 2048, overlap: float = 0.5,
             window: str = "hann") -> dict:
    """The Welch averaging `transfer_function` uses, as keywords of scipy.signal's `csd` and
    `welch` (for a caller that keeps a spectrum it reuses)."""
    return {"fs": fs, "window": window, "nperseg": nperseg,
            "noverlap": round(overlap * nperseg)}


def transfer_function(x: np.ndarray, y: np.ndarray, fs: float, nperseg: int = 2048,
                      overlap: float = 0.5, integrate: int = 0,
                      window: str = "hann") -> TransferFunction:
    """H1 estimate of y/x (eqs 3.1a-c) with coherence (eq 3.2).

    `integrate` = 2 divides H by -ω² (displacement from a measured acceleration, §3.4.1).
    `window` = "boxcar" with `overlap` = 0 suits periodic excitation analysed over whole
    periods (no leakage).
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.shape != y.shape or x.ndim != 1:
        raise VtableError("input and output must be 1-D histories of the same length")
    if len(x) < nperseg:
        raise VtableError(f"{len(x)} samples are shorter than one {nperseg}-point frame")
    kw = welch_kw(fs, nperseg, overlap, window)
    f, Gxy = scipy.signal.csd(x, y, **kw)
    _, Gxx = scipy.signal.welch(x, **kw)
    _, Gyy = scipy.signal.welch(y, **kw)
    with np.errstate(divide="ignore", invalid="ignore"):
        H = Gxy / Gxx
        coh = np.abs(Gxy) ** 2 / (Gxx * Gyy)
        if integrate:
            w = 2 * np.pi * f
            H = H / (1j * w) ** integrate
    step = nperseg - kw["noverlap"]
    return TransferFunction(f, H, np.nan_to_num(coh), 1 + (len(x) - nperseg) // step)


def transfer_function_via(ref: np.ndarray, x: np.ndarray, y: np.ndarray, fs: float,
                          nperseg: int = 2048, overlap: float = 0.5,
                          window: str = "hann") -> TransferFunction:
    """y/x as (y/ref)/(x/ref) = G_ry/G_rx: with a noise-free reference (the command) the
    sensor noise on x and y averages out instead of biasing the estimate, as it biases
    H1 where x is weak (an instrumental-variable estimate). Coherence: the product of
    the two coherences."""
    a = transfer_function(ref, x, fs, nperseg, overlap, window=window)
    b = transfer_function(ref, y, fs, nperseg, overlap, window=window)
    with np.errstate(divide="ignore", invalid="ignore"):
        return TransferFunction(a.f, b.H / a.H, a.coherence * b.coherence, a.averages)
