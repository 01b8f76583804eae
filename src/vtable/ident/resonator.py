"""identify's resonator structure (`vtable.ident.loop`, "resonator": eq 7.9 with the
valve lag, `vtable.ident.fits.h_resonator_lag`): where its fits start, and when a fit
found a resonance rather than patched a loop the other structures cannot reach."""

from __future__ import annotations

import numpy as np

from vtable.ident.fits import Fit

#: a fitted resonator counts as one only with ξ_s up to this (a peak and a notch)
RESONANCE_MAX_DAMPING = 0.3


def is_resonance(fit: Fit) -> bool:
    """A resonator fit that found a resonance: ξ_s ≤ `RESONANCE_MAX_DAMPING` and none of
    f_s, ξ_s, u flagged (at a bound — u's upper one is the table's payload — or a standard
    error beyond the value): else the extra freedom only patched a loop the other
    structures cannot reach (a PI controller's low-frequency peak asks for a 10 t
    resonator on LNEC's 5 t table)."""
    if fit["xi_s"] > RESONANCE_MAX_DAMPING:
        return False
    return not any(f.param in ("f_s", "xi_s", "u") and f.code != "correlated"
                   for f in fit.flags)


def dip(data) -> float:
    """The frequency of the deepest dip of |H| relative to its running trend (a
    resonator's notch), among the lines below 80 % of the highest."""
    m = np.abs(data.H)
    k = data.f < 0.8 * data.f[-1]
    if k.sum() < 5 or len(m) < 9:
        return float(data.f[len(data.f) // 2])
    trend = np.convolve(m, np.ones(9) / 9, mode="same")
    r = np.where(k, m / np.maximum(trend, 1e-12), np.inf)
    return float(data.f[int(np.argmin(r))])
