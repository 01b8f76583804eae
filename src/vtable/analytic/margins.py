"""Gain and phase margins of the report's tracking loop (§6.8, §7.7).

The report's open loop is the unity-feedback loop L = H/(1 - H) (eq 6.21), H = x_t/x_c.
Gain margin: 1/|L| where L crosses the negative real axis; phase margin: 180° + ∠L where
|L| = 1. Where there are several crossings the smallest margin is the one reported.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq


@dataclass(frozen=True)
class Margins:
    """Stability margins of L = H/(1-H); frequencies in Hz, phase in degrees."""

    gain_margin: float
    phase_margin: float
    f_phase_crossover: float  # where ∠L = -180° (gain margin read here)
    f_gain_crossover: float  # where |L| = 1 (phase margin read here)
    all_gain_margins: tuple[float, ...] = ()
    all_phase_margins: tuple[float, ...] = ()


def open_loop_from_closed(H: np.ndarray) -> np.ndarray:
    """L = H/(1 - H), eq 6.21."""
    return H / (1.0 - H)


def loop_margins(L: Callable[[np.ndarray], np.ndarray], f_min: float = 1e-3,
                 f_max: float = 1e3, n: int = 20001) -> Margins:
    """Margins of the loop L(f) (vectorised in f, Hz), crossings refined with brentq."""
    f = np.logspace(np.log10(f_min), np.log10(f_max), n)
    Lf = L(f)

    def refine(g: Callable[[float], float], i: int) -> float:
        return brentq(g, f[i], f[i + 1], xtol=1e-12, rtol=1e-13)

    def L1(x: float) -> complex:
        return complex(L(np.array([x]))[0])

    gms, f_gms = [], []
    im = Lf.imag
    for i in np.nonzero(np.sign(im[:-1]) * np.sign(im[1:]) < 0)[0]:
        fc = refine(lambda x: L1(x).imag, i)
        z = L1(fc)
        if z.real < 0:
            gms.append(-1.0 / z.real)
            f_gms.append(fc)
    pms, f_pms = [], []
    mag = np.abs(Lf) - 1.0
    for i in np.nonzero(np.sign(mag[:-1]) * np.sign(mag[1:]) < 0)[0]:
        fc = refine(lambda x: abs(L1(x)) - 1.0, i)
        pms.append(180.0 + np.degrees(np.angle(L1(fc))))
        f_pms.append(fc)
    gi = int(np.argmin(gms)) if gms else None
    pi = int(np.argmin(pms)) if pms else None
    return Margins(
        gain_margin=gms[gi] if gi is not None else np.inf,
        phase_margin=pms[pi] if pi is not None else np.inf,
        f_phase_crossover=f_gms[gi] if gi is not None else np.nan,
        f_gain_crossover=f_pms[pi] if pi is not None else np.nan,
        all_gain_margins=tuple(gms), all_phase_margins=tuple(pms))
