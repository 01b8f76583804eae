"""Elastic SDOF response spectra by the exact recurrence for piecewise-linear excitation
(Nigam & Jennings 1969), vectorized over periods, compiled with numba."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vtable._numba import njit
from vtable.analytic.hold import first_order_hold
from vtable.errors import VtableError
from vtable.runs.model import FORMAT_UNITS


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


def nigam_jennings(periods: np.ndarray, damping: float, dt: float):
    """Φ (n,2,2), G0 and G1 (n,2) of x_{k+1} = Φ x_k + G0 a_k + G1 a_{k+1} in the closed
    form of Nigam & Jennings (1969) for ü + 2ξωu̇ + ω²u = -a, a linear over each step."""
    w = 2 * np.pi / np.asarray(periods, dtype=float)
    xi = damping
    wd = w * np.sqrt(1 - xi * xi)
    E, S, C = np.exp(-xi * w * dt), np.sin(wd * dt), np.cos(wd * dt)
    Phi = np.empty((len(w), 2, 2))
    Phi[:, 0, 0] = E * (xi * w / wd * S + C)
    Phi[:, 0, 1] = E * S / wd
    Phi[:, 1, 0] = -w / np.sqrt(1 - xi * xi) * E * S
    Phi[:, 1, 1] = E * (C - xi * w / wd * S)
    p = (2 * xi * xi - 1) / (w * w * dt)
    q = 2 * xi / (w**3 * dt)
    G0, G1 = np.empty((len(w), 2)), np.empty((len(w), 2))
    G0[:, 0] = E * ((p + xi / w) * S / wd + (q + 1 / w**2) * C) - q
    G1[:, 0] = -E * (p * S / wd + q * C) - 1 / w**2 + q
    G0[:, 1] = (E * ((p + xi / w) * (C - xi * w / wd * S) - (q + 1 / w**2)
                     * (wd * S + xi * w * C)) + 1 / (w * w * dt))
    G1[:, 1] = -E * (p * (C - xi * w / wd * S) - q * (wd * S + xi * w * C)) - 1 / (w * w * dt)
    return Phi, G0, G1


def recurrence(periods: np.ndarray, damping: float, dt: float):
    """The same recurrence derived independently: each oscillator stepped exactly with its
    input linear over the step (`first_order_hold`; used to check the closed form)."""
    w = 2 * np.pi / np.asarray(periods, dtype=float)
    b = np.array([0.0, -1.0])  # input a
    holds = [first_order_hold(np.array([[0.0, 1.0], [-wi * wi, -2 * damping * wi]]), b, dt)
             for wi in w]
    Phi, gam, lam = (np.array(x) for x in zip(*holds, strict=True))
    return Phi, gam - lam, lam


@njit(cache=True)
def _peaks(acc, Phi, G0, G1):
    n_p = Phi.shape[0]
    out = np.zeros(n_p)
    for p in range(n_p):
        f00, f01, f10, f11 = Phi[p, 0, 0], Phi[p, 0, 1], Phi[p, 1, 0], Phi[p, 1, 1]
        a0, a1, b0, b1 = G0[p, 0], G0[p, 1], G1[p, 0], G1[p, 1]
        u = 0.0
        v = 0.0
        peak = 0.0
        for k in range(acc.shape[0] - 1):
            ak, ak1 = acc[k], acc[k + 1]
            u, v = f00 * u + f01 * v + a0 * ak + b0 * ak1, f10 * u + f11 * v + a1 * ak + b1 * ak1
            if abs(u) > peak:
                peak = abs(u)
        out[p] = peak
    return out


def response_spectrum(acc: np.ndarray, dt: float, periods, damping: float = 0.05) -> Spectrum:
    """Peak relative displacement of SDOF oscillators under ground acceleration `acc`
    (m/s², uniform step dt), from rest."""
    periods = np.atleast_1d(np.asarray(periods, dtype=float))
    if np.any(periods <= 0) or not dt > 0:
        raise VtableError("periods and dt must be > 0")
    if not 0 <= damping < 1:
        raise VtableError(f"damping must be in [0, 1), got {damping!r}")
    acc = np.ascontiguousarray(acc, dtype=float)
    Phi, G0, G1 = nigam_jennings(periods, damping, dt)
    return Spectrum(periods, damping, _peaks(acc, Phi, G0, G1))


def _check_acceleration(run, name: str) -> np.ndarray:
    unit = run.units.get(name, FORMAT_UNITS.get(name, ""))
    if unit not in ("g", "m/s2", "rad/s2"):
        raise VtableError(f"{run.name}: channel {name!r} is not an acceleration (unit "
                          f"{unit or 'unknown'}); a response spectrum needs one")
    return run.channel(name)


def channel_spectrum(run, channel: str, periods, damping: float = 0.05) -> Spectrum:
    """Spectrum of one acceleration channel of a run (SI, e.g. ``avg_hacc``)."""
    return response_spectrum(_check_acceleration(run, channel), run.dt, periods, damping)


def effective_motion(run, height: float) -> np.ndarray:
    """ẍ_t + h θ̈ (m/s²): the base acceleration a specimen whose mass sits `height` (m)
    above the actuator line feels on a pitching table (§8.6.4, x_eff = x_t + θh)."""
    return _check_acceleration(run, "avg_hacc") + height * _check_acceleration(run, "pitch_acc")


def effective_spectrum(run, height: float, periods, damping: float = 0.05) -> Spectrum:
    """Spectrum of the effective base motion x_t + hθ of a run."""
    return response_spectrum(effective_motion(run, height), run.dt, periods, damping)
