"""Command signals: band-limited random, sine and pulse displacement histories (SI)."""

from __future__ import annotations

import numpy as np

from vtable.errors import VtableError


def time_axis(duration: float, dt: float) -> np.ndarray:
    """0, dt, ..., up to and including `duration` (to within dt/2)."""
    if not (dt > 0 and duration > 0):
        raise VtableError(f"duration and dt must be > 0 (got {duration!r}, {dt!r})")
    return np.arange(round(duration / dt) + 1) * dt


def band_limited_random(duration: float, dt: float, band: tuple[float, float] = (0.0, 25.0),
                        peak: float | None = None, rms: float | None = None,
                        seed: int = 0, period: float | None = None
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Random displacement with a flat amplitude spectrum in `band` (Hz) and random phases.

    Reproducible from `seed` (numpy's default generator). Scaled to `peak` (max |x|) or
    `rms`; with neither, unit rms. The report used 0-25 and 0-32 Hz bands (§3.2, §6.7).
    With `period` (s, a multiple of dt) the signal repeats exactly with that period
    ("periodic random"), so transfer functions over whole periods have no leakage.
    """
    if peak is not None and rms is not None:
        raise VtableError("give peak or rms, not both")
    t = time_axis(duration, dt)
    if period is not None:
        n_p = round(period / dt)
        if n_p < 2 or abs(n_p * dt - period) > 1e-9 * period:
            raise VtableError(f"period {period!r} s must be a multiple of dt = {dt!r} s")
        _, one = band_limited_random(period - dt, dt, band, None, None, seed)
        return t, _scaled(np.resize(one, len(t)) / np.sqrt(np.mean(one**2)), peak, rms)
    lo, hi = band
    nyq = 0.5 / dt
    if not (0 <= lo < hi <= nyq):
        raise VtableError(f"band {band} must satisfy 0 <= low < high <= Nyquist {nyq:g} Hz")
    f = np.fft.rfftfreq(len(t), dt)
    inband = (f >= lo) & (f <= hi) & (f > 0)
    rng = np.random.default_rng(seed)
    spec = np.zeros(len(f), dtype=complex)
    spec[inband] = np.exp(2j * np.pi * rng.random(int(inband.sum())))
    x = np.fft.irfft(spec, n=len(t))
    return t, _scaled(x / np.sqrt(np.mean(x**2)), peak, rms)


def _scaled(x: np.ndarray, peak: float | None, rms: float | None) -> np.ndarray:
    """Unit-rms `x` scaled to `peak` (max |x|) or `rms`, or left at unit rms."""
    if peak is not None:
        return x * (peak / np.max(np.abs(x)))
    return x * rms if rms is not None else x


def sine(duration: float, dt: float, frequency: float, amplitude: float,
         ramp: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """amplitude·sin(2πft), optionally with cosine ramps of `ramp` seconds at both ends."""
    if not frequency > 0:
        raise VtableError(f"sine frequency must be > 0, got {frequency!r}")
    t = time_axis(duration, dt)
    x = amplitude * np.sin(2 * np.pi * frequency * t)
    return t, x * _ramps(t, ramp)


def pulse(duration: float, dt: float, width: float, amplitude: float,
          start: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A smooth displacement pulse: a Hann (raised-cosine) bump of `width` seconds and
    height `amplitude` starting at `start`; zero displacement and velocity at both ends."""
    t = time_axis(duration, dt)
    if not (width > 0 and 0 <= start and start + width <= t[-1] + dt / 2):
        raise VtableError("the pulse must have width > 0 and fit inside the duration")
    tau = (t - start) / width
    x = np.where((tau >= 0) & (tau <= 1), 0.5 * (1 - np.cos(2 * np.pi * tau)), 0.0)
    return t, amplitude * x


def _ramps(t: np.ndarray, ramp: float) -> np.ndarray:
    if ramp <= 0:
        return np.ones_like(t)
    w = np.ones_like(t)
    up = t < ramp
    w[up] = 0.5 * (1 - np.cos(np.pi * t[up] / ramp))
    down = t > t[-1] - ramp
    w[down] = 0.5 * (1 - np.cos(np.pi * (t[-1] - t[down]) / ramp))
    return w
