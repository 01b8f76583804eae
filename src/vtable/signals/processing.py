"""The report's record processing for table commands (§9.2).

Scale length and time (model/prototype, e.g. length 3.2801, time 1.811 = √3.2801),
optionally band-pass, integrate to displacement with zero initial and final displacement
and velocity, scale to a displacement range, and differentiate back to acceleration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.integrate

from vtable.errors import VtableError
from vtable.signals.records import Record


def scale_record(rec: Record, length_scale: float, time_scale: float | None = None) -> Record:
    """Similitude scaling: prototype/model length factor λ_L and time factor λ_T
    (default √λ_L). Time is compressed by λ_T; acceleration scales by λ_T²/λ_L... i.e.
    a_model = a_proto · λ_T²/λ_L (1 when λ_T = √λ_L)."""
    if not length_scale > 0:
        raise VtableError(f"length scale must be > 0, got {length_scale!r}")
    lt = np.sqrt(length_scale) if time_scale is None else time_scale
    if not lt > 0:
        raise VtableError(f"time scale must be > 0, got {time_scale!r}")
    return Record(f"{rec.name} (L/{length_scale:g}, T/{lt:g})", rec.dt / lt,
                  rec.acc * lt**2 / length_scale)


def bandpass_trapezoid(acc: np.ndarray, dt: float, corners: tuple[float, float, float, float]
                       ) -> np.ndarray:
    """Zero-phase FFT band-pass with a trapezoidal gain through the four corner
    frequencies f1 < f2 <= f3 < f4 Hz (e.g. 0.5, 0.55, 23, 24 Hz, §9.2)."""
    f1, f2, f3, f4 = corners
    if not 0 <= f1 < f2 <= f3 < f4:
        raise VtableError(f"band-pass corners must increase, got {corners}")
    n = len(acc)
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    f = np.fft.rfftfreq(nfft, dt)
    gain = np.interp(f, [f1, f2, f3, f4], [0.0, 1.0, 1.0, 0.0], left=0.0, right=0.0)
    return np.fft.irfft(np.fft.rfft(acc, nfft) * gain, nfft)[:n]


def integrate_to_displacement(acc: np.ndarray, dt: float) -> np.ndarray:
    """Double trapezoidal integration, then subtraction of the cubic c(t) that makes the
    displacement and velocity zero at both ends (a linear baseline in acceleration)."""
    v = scipy.integrate.cumulative_trapezoid(acc, dx=dt, initial=0.0)
    d = scipy.integrate.cumulative_trapezoid(v, dx=dt, initial=0.0)
    T = (len(acc) - 1) * dt
    t = np.arange(len(acc)) * dt
    # c(0) = c'(0) = 0, c(T) = d(T), c'(T) = v(T)  ->  c = a t² + b t³
    dT, vT = d[-1], v[-1]
    b = (vT * T - 2 * dT) / T**3
    a = (dT - b * T**3) / T**2
    return d - (a * t**2 + b * t**3)


def differentiate(x: np.ndarray, dt: float, scheme: str = "central") -> np.ndarray:
    """Second derivative: central differences (second order, one-sided at the ends) or
    first-order forward differences, the two schemes of §9.2."""
    if scheme == "central":
        return np.gradient(np.gradient(x, dt, edge_order=2), dt, edge_order=2)
    if scheme == "forward":
        v = np.diff(x, append=x[-1]) / dt
        return np.diff(v, append=v[-1]) / dt
    raise VtableError(f"unknown differentiation scheme {scheme!r}; expected central or forward")


@dataclass(frozen=True)
class TableCommand:
    """A displacement command and its acceleration (SI), uniform step dt."""

    name: str
    dt: float
    displacement: np.ndarray
    acceleration: np.ndarray

    @property
    def time(self) -> np.ndarray:
        return np.arange(len(self.displacement)) * self.dt


def process_record(rec: Record, *, length_scale: float = 3.2801,
                   time_scale: float | None = None, peak_displacement: float = 4 * 0.0254,
                   window: tuple[float, float] | None = None,
                   corners: tuple[float, float, float, float] | None = None,
                   scheme: str = "central", scale_as_whole: bool = False) -> TableCommand:
    """§9.2: take the `window` (s, prototype time), scale, band-pass (optional), integrate
    with zero end conditions, scale to `peak_displacement` (max |x_c|; 4 in by default),
    and differentiate back to the command acceleration. With `scale_as_whole` a window is
    scaled by the factor that brings the whole record's displacement to
    `peak_displacement`: the part then shakes as it does within the whole record (its own
    peak is at most that)."""
    if not peak_displacement > 0:
        raise VtableError("peak displacement must be > 0")
    acc = rec.acc
    if window is not None:
        t0, t1 = window
        i0, i1 = round(t0 / rec.dt), round(t1 / rec.dt) + 1
        if not (0 <= i0 < i1 <= len(acc)):
            raise VtableError(f"window {window} s is outside the record (0-{rec.duration:g} s)")
        acc = acc[i0:i1]

    def displacement(a: np.ndarray) -> tuple[Record, np.ndarray]:
        scaled = scale_record(Record(rec.name, rec.dt, a), length_scale, time_scale)
        b = scaled.acc if corners is None else bandpass_trapezoid(scaled.acc, scaled.dt,
                                                                   corners)
        return scaled, integrate_to_displacement(b, scaled.dt)

    scaled, d = displacement(acc)
    whole = displacement(rec.acc)[1] if window is not None and scale_as_whole else d
    d *= peak_displacement / np.max(np.abs(whole))
    return TableCommand(scaled.name, scaled.dt, d, differentiate(d, scaled.dt, scheme))
