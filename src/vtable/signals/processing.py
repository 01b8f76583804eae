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
                   scheme: str = "central") -> TableCommand:
    """§9.2: take the `window` (s, prototype time), scale, band-pass (optional), integrate
    with zero end conditions, scale to `peak_displacement` (max |x_c|; 4 in by default),
    and differentiate back to the command acceleration. A window is processed on its own
    (its own end conditions and peak); `first_seconds` instead cuts the processed whole."""
    if not peak_displacement > 0:
        raise VtableError("peak displacement must be > 0")
    acc = rec.acc
    if window is not None:
        t0, t1 = window
        i0, i1 = round(t0 / rec.dt), round(t1 / rec.dt) + 1
        if not (0 <= i0 < i1 <= len(acc)):
            raise VtableError(f"window {window} s is outside the record (0-{rec.duration:g} s)")
        acc = acc[i0:i1]
    scaled = scale_record(Record(rec.name, rec.dt, acc), length_scale, time_scale)
    a = scaled.acc if corners is None else bandpass_trapezoid(scaled.acc, scaled.dt, corners)
    d = integrate_to_displacement(a, scaled.dt)
    d *= peak_displacement / np.max(np.abs(d))
    return TableCommand(scaled.name, scaled.dt, d, differentiate(d, scaled.dt, scheme))


#: the longest stretch (s, table time) over which `first_seconds` brings a cut to rest
REST_SECONDS = 2.0


def to_rest(x: np.ndarray, dt: float, seconds: float) -> np.ndarray:
    """`x` brought to rest (zero displacement and velocity) at its last sample by
    subtracting, over its last `seconds`, c = x_T p(s) + v_T·τ q(s) (s from 0 to 1 over
    those τ seconds; p = 4s³ - 3s⁴, q = s⁴ - s³): c, c' and c'' are zero where it starts
    (the acceleration stays continuous) and c = x_T, c' = v_T at the end; before it `x` is
    untouched. The added acceleration is x_T p''/τ² + v_T q''/τ, at most 12|x_T|/τ² +
    6|v_T|/τ."""
    n = len(x)
    m = min(n - 1, max(1, round(seconds / dt)))
    tau = m * dt
    s = np.linspace(0.0, 1.0, m + 1)
    v_end = np.gradient(x, dt, edge_order=2)[-1]
    c = x[-1] * (4 * s**3 - 3 * s**4) + v_end * tau * (s**4 - s**3)
    out = np.array(x, dtype=float)
    out[n - m - 1:] -= c
    return out


def first_seconds(cmd: TableCommand, seconds: float, scheme: str = "central") -> TableCommand:
    """The first `seconds` of a processed command as the whole plays them: the same
    displacement, scaled as the whole was, brought to rest over its last `REST_SECONDS`
    (a third of a shorter part) by `to_rest`. Processing the part on its own instead
    (`process_record(window=...)`) gives it its own end conditions, whose cubic baseline
    over the part can double its displacement, and its own scaling."""
    n = min(len(cmd.displacement), round(seconds / cmd.dt) + 1)
    if n < 4:
        raise VtableError(f"{seconds:g} s is too short a part of {cmd.name} (step "
                          f"{cmd.dt:.4g} s)")
    d = to_rest(cmd.displacement[:n], cmd.dt, min(REST_SECONDS, (n - 1) * cmd.dt / 3))
    return TableCommand(cmd.name, cmd.dt, d, differentiate(d, cmd.dt, scheme))
