"""Elastic SDOF response spectra by the exact recurrence for piecewise-linear excitation
(Nigam & Jennings), vectorized over periods."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from vtable.errors import VtableError


@dataclass(frozen=True)
class Spectrum:
    """SD (m), PSV = ωSD (m/s) and PSA = ω²SD (m/s²) at `periods` (s), damping ξ."""

    periods: np.ndarray
    damping: float
    sd: np.ndarray

    @property
    def psv(self) -> np.ndarray:
        return 2 * np.pi / self.periods * self.sd

    @property
    def psa(self) -> np.ndarray:
        return (2 * np.pi / self.periods) ** 2 * self.sd


def _recurrence(periods: np.ndarray, damping: float, dt: float):
    """Φ, G0, G1 per period: x_{k+1} = Φ x_k + G0 a_k + G1 a_{k+1} for
    ü + 2ξωu̇ + ω²u = -a with a linear over each step (exact)."""
    n = len(periods)
    Phi, G0, G1 = np.empty((n, 2, 2)), np.empty((n, 2)), np.empty((n, 2))
    for i, T in enumerate(periods):
        w = 2 * np.pi / T
        M = np.zeros((4, 4))
        M[0, 1] = 1.0
        M[1, 0], M[1, 1] = -w * w, -2 * damping * w
        M[1, 2] = -1.0  # input a
        M[2, 3] = 1.0  # a varies with slope δ
        E = scipy.linalg.expm(M * dt)
        Phi[i] = E[:2, :2]
        g, lam = E[:2, 2], E[:2, 3] / dt  # per a_k, per (a_{k+1} - a_k)
        G0[i], G1[i] = g - lam, lam
    return Phi, G0, G1


def response_spectrum(acc: np.ndarray, dt: float, periods, damping: float = 0.05) -> Spectrum:
    """Peak relative displacement of SDOF oscillators under ground acceleration `acc`."""
    periods = np.asarray(periods, dtype=float)
    if np.any(periods <= 0) or not dt > 0:
        raise VtableError("periods and dt must be > 0")
    if not 0 <= damping < 1:
        raise VtableError(f"damping must be in [0, 1), got {damping!r}")
    acc = np.asarray(acc, dtype=float)
    Phi, G0, G1 = _recurrence(periods, damping, dt)
    x = np.zeros((len(periods), 2))
    peak = np.zeros(len(periods))
    for k in range(len(acc) - 1):
        x = np.einsum("pij,pj->pi", Phi, x) + G0 * acc[k] + G1 * acc[k + 1]
        np.maximum(peak, np.abs(x[:, 0]), out=peak)
    return Spectrum(periods, damping, peak)
