"""Whether a run's table channels describe one rigid platen: the measured table
acceleration against the second derivative of the measured table displacement.

Every model vtable fits moves one platen, so its ẍ_t is s² x_t. A run whose
accelerometer and displacement transducer disagree beyond that — the accelerometer on a
compliant mount or a bending platen, a filter in one conditioning chain only — leaves a
residual no effect on the platen can remove. This module measures the disagreement

    R(f) = H_ad(f) / (-ω²),   H_ad = S_da / S_dd  (H1 of acceleration over displacement),

band by band where the two channels are coherent (a rigid platen with ideal sensors has
R = 1), and, when R departs from 1, fits the simplest physics that makes it: the
accelerometer on a mount of one resonance ω_m, ζ_m behind a second-order low-pass ω_c
(its conditioning),

    R(s) = ω_m² / (s² + 2 ζ_m ω_m s + ω_m²) · ω_c² / (s² + √2 ω_c s + ω_c²).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize
import scipy.signal

from vtable.diagnose.groups import group_signal
from vtable.diagnose.sampling import BANDS
from vtable.effects.sensor import mount_log_derivatives, mount_response
from vtable.runs.model import Run

#: the two channels are compared where their coherence is at least this
COHERENCE = 0.9
#: |R - 1| in a band (median over its coherent lines) beyond which the channels disagree
TOLERANCE = 0.15
#: frequency resolution of the spectra (Hz): fine enough for a mount resonance's peak
RESOLUTION_HZ = 0.1


@dataclass(frozen=True)
class SensorCheck:
    """A run's table acceleration against its displacement's second derivative.

    `bands` holds (label, |R| median, phase median in degrees, coherent lines) per band
    with coherent lines; `mount` the fitted (f_m Hz, ζ_m, f_c Hz) and `misfit` the fit's
    rms error on log R, when the channels disagree."""

    run: str
    bands: tuple[tuple[str, float, float, int], ...]
    mount: tuple[float, float, float] | None = None
    misfit: float | None = None

    @property
    def agree(self) -> bool:
        return all(abs(m - 1) <= TOLERANCE for _, m, _, _ in self.bands)

    def text(self) -> str:
        """One line for the notes and the verdict."""
        if self.agree:
            return (f"{self.run}: table acceleration and displacement agree (|ẍ/s²x| within "
                    f"{TOLERANCE:.0%} of 1 in every coherent band)")
        ratios = ", ".join(f"{m:.2f} at {b}" for b, m, _, _ in self.bands)
        out = (f"{self.run}: the table acceleration is not the second derivative of the "
               f"table displacement (|ẍ/s²x| {ratios}): the two sensors do not see one rigid "
               "platen, and no effect on the platen can fit both channels (sensor_mount, "
               "a filter on the acceleration channel alone, can)")
        if self.mount is not None:
            f_m, z_m, f_c = self.mount
            out += (f"; as an accelerometer on a mount, fitted: resonance {f_m:.1f} Hz, "
                    f"damping {z_m:.3f}, behind a {f_c:.1f} Hz low-pass (rms misfit "
                    f"{self.misfit:.1%}); score one of the two channels, or fix the mount")
        return out


def mount_ratio(f: np.ndarray, f_m: float, z_m: float, f_c: float) -> np.ndarray:
    """R(f) of the module docstring (`vtable.effects.sensor.mount_response`: the law the
    sensor_mount effect applies)."""
    return mount_response(2 * math.pi * np.asarray(f, dtype=float), f_m, z_m, f_c)


def sensor_check(run: Run) -> SensorCheck | None:
    """Whether `run`'s table acceleration is its table displacement's second derivative.

    Parameters
    ----------
    run
        A measured or simulated run with the "table displacement" and "table
        acceleration" channel groups (`vtable.diagnose.groups`).

    Returns
    -------
    SensorCheck or None
        |R| and its phase per band (`BANDS`) where the channels are coherent
        (γ² ≥ `COHERENCE`), and, when some band departs from 1 by more than `TOLERANCE`,
        the fitted mount (f_m, ζ_m, f_c) of the module docstring; None when the run
        lacks either channel or has no coherent band.
    """
    d = group_signal(run, "table displacement")
    a = group_signal(run, "table acceleration")
    if d is None or a is None:
        return None
    fs = run.fs
    nper = min(len(d) // 4, 1 << math.ceil(math.log2(fs / RESOLUTION_HZ)))
    if nper < 64:
        return None
    f, s_dd = scipy.signal.welch(d, fs, nperseg=nper)
    _, s_aa = scipy.signal.welch(a, fs, nperseg=nper)
    _, s_da = scipy.signal.csd(d, a, fs, nperseg=nper)
    ok = (f > 0) & (s_dd > 0) & (s_aa > 0)
    coh = np.zeros_like(f)
    coh[ok] = np.abs(s_da[ok]) ** 2 / (s_dd[ok] * s_aa[ok])
    w = 2 * math.pi * f
    R = np.full(len(f), np.nan, dtype=complex)
    R[ok] = s_da[ok] / s_dd[ok] / -(w[ok] ** 2)
    good = ok & (coh >= COHERENCE)
    bands = []
    for lo, hi in BANDS:
        k = good & (f >= max(lo, 0.5)) & (f < min(hi, 0.4 * fs))
        if k.sum() >= 3:
            bands.append((f"{lo:g}-{hi:g} Hz", float(np.median(np.abs(R[k]))),
                          float(np.degrees(np.median(np.angle(R[k])))), int(k.sum())))
    if not bands:
        return None
    check = SensorCheck(run.name, tuple(bands))
    if check.agree:
        return check
    k = good & (f >= 0.5) & (f < 0.4 * fs)
    fk, Rk = f[k], R[k]

    def residual(p):
        e = np.log(mount_ratio(fk, *p) / Rk)
        return np.concatenate([e.real, e.imag])

    wk = 2 * math.pi * fk

    def jacobian(p):  # the law's own derivatives (forward differences: 3 more residuals)
        J = mount_log_derivatives(wk, *p)
        return np.concatenate([J.real, J.imag])

    f_hi = float(fk.max())
    starts = [(f_m, 0.1, 2 * f_hi) for f_m in np.geomspace(2.0, 0.9 * f_hi, 8)]
    best = None
    for p0 in starts:
        try:
            r = scipy.optimize.least_squares(residual, p0, jac=jacobian,
                                             bounds=([0.5, 0.005, 1.0], [f_hi * 2, 2.0, fs / 2]))
        except ValueError:
            continue
        if best is None or r.cost < best.cost:
            best = r
    if best is None:
        return check
    misfit = float(np.sqrt(np.mean(residual(best.x) ** 2)))
    return SensorCheck(run.name, tuple(bands), tuple(float(v) for v in best.x), misfit)
