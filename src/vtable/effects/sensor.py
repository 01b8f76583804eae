"""The measurement chain's analog filters, applied the same way to the virtual table's and
the reduced model's response channels: the anti-aliasing filter (report §2.3: 100 Hz analog
low-pass before sampling), and an accelerometer's mount and conditioner (`mount_ba`). The
anti-aliasing filter is the analog 4-pole Butterworth (order assumed) applied exactly in the
frequency domain (an FFT zero-padded by ten periods of the cut-off) at the simulation rate,
before decimation. Being the analog response, the result does not depend on the simulation
rate."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.fft
import scipy.signal

ORDER = 4


@lru_cache(maxsize=64)
def _response(nfft: int, fs: float, ba: tuple[tuple[float, ...], tuple[float, ...]]
              ) -> np.ndarray:
    """The analog filter (b, a)'s response on the FFT's frequencies (read-only: shared)."""
    w = 2 * np.pi * np.fft.rfftfreq(nfft, 1.0 / fs)
    _, H = scipy.signal.freqs(*ba, worN=w)
    H.flags.writeable = False
    return H


@lru_cache(maxsize=256)
def butterworth_ba(cutoff_hz: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The anti-aliasing low-pass: an analog `ORDER`-pole Butterworth at `cutoff_hz` (kept:
    a fit's forward differences ask for the same cut-off once per other parameter)."""
    b, a = scipy.signal.butter(ORDER, 2 * np.pi * cutoff_hz, analog=True)
    return tuple(map(float, b)), tuple(map(float, a))


def _mount_sections(f_m: float, z_m: float, f_c: float
                    ) -> tuple[tuple[float, float], tuple[float, float]]:
    """An accelerometer on a mount of one resonance (f_m Hz, damping ratio z_m) behind its
    conditioner's second-order Butterworth low-pass at f_c Hz: what the acceleration
    channel reads over the platen's acceleration,

        R(s) = ω_m² / (s² + 2 ζ_m ω_m s + ω_m²) · ω_c² / (s² + √2 ω_c s + ω_c²),

    as its two sections' (ω², 2ζω)."""
    wm, wc = 2 * np.pi * f_m, 2 * np.pi * f_c
    return (wm**2, 2 * z_m * wm), (wc**2, np.sqrt(2) * wc)


def mount_ba(f_m: float, z_m: float, f_c: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The mount's R(s) (`_mount_sections`) as an analog (b, a)."""
    (m0, m1), (c0, c1) = _mount_sections(f_m, z_m, f_c)
    a = np.polymul([1.0, m1, m0], [1.0, c1, c0])
    return (float(m0 * c0),), tuple(map(float, a))


def mount_response(w: np.ndarray, f_m: float, z_m: float, f_c: float) -> np.ndarray:
    """The mount's R(jω) at the angular frequencies `w` (rad/s), section by section
    (`_mount_sections`; `mount_ba` multiplied out): a fit evaluates it a thousand times."""
    s = 1j * np.asarray(w, dtype=float)
    r = np.ones(len(s), dtype=complex)
    for w0, c in _mount_sections(f_m, z_m, f_c):
        r *= w0 / (s * s + c * s + w0)
    return r


def mount_log_derivatives(w: np.ndarray, f_m: float, z_m: float, f_c: float) -> np.ndarray:
    """∂ ln R(jω) / ∂(f_m, ζ_m, f_c) at the angular frequencies `w` (`mount_response`),
    one column each: with D_m = s² + 2ζ_mω_m s + ω_m² and D_c = s² + √2ω_c s + ω_c²,
    ln R = 2 ln ω_m − ln D_m + 2 ln ω_c − ln D_c, so

        ∂/∂f_m = 2π (2/ω_m − (2ζ_m s + 2ω_m)/D_m),   ∂/∂ζ_m = −2ω_m s/D_m,
        ∂/∂f_c = 2π (2/ω_c − (√2 s + 2ω_c)/D_c).

    A fit of ln R (the sensor check's) takes them as its Jacobian, where forward
    differences cost it three evaluations a step."""
    s = 1j * np.asarray(w, dtype=float)
    wm, wc = 2 * np.pi * f_m, 2 * np.pi * f_c
    d_m = s * s + 2 * z_m * wm * s + wm * wm
    d_c = s * s + np.sqrt(2) * wc * s + wc * wc
    return np.stack([2 * np.pi * (2 / wm - (2 * z_m * s + 2 * wm) / d_m),
                     -2 * wm * s / d_m,
                     2 * np.pi * (2 / wc - (np.sqrt(2) * s + 2 * wc) / d_c)], axis=1)


def analog_filter(x: np.ndarray, fs: float,
                  ba: tuple[tuple[float, ...], tuple[float, ...]], slowest_hz: float
                  ) -> np.ndarray:
    """`x` sampled at `fs` through the analog filter `ba`, exactly in the frequency domain
    (zero-padded by `PAD_PERIODS` periods of `slowest_hz`, its slowest pole's frequency)."""
    x = np.asarray(x, dtype=float)
    n = len(x)
    nfft = scipy.fft.next_fast_len(n + max(64, int(np.ceil(PAD_PERIODS * fs / slowest_hz))),
                                   real=True)
    H = _response(nfft, float(fs), ba)
    return scipy.fft.irfft(scipy.fft.rfft(x, nfft) * H, nfft)[:n]


#: zero padding, in periods of the cut-off: the filter's slowest poles decay as
#: exp(-sin(π/8) ω_c t), to 1e-10 of their start in 9.6 periods
PAD_PERIODS = 10.0


def sensor_filter(x: np.ndarray, fs: float, cutoff_hz: float) -> np.ndarray:
    """`x` through the anti-aliasing low-pass (`butterworth_ba`)."""
    return analog_filter(x, fs, butterworth_ba(float(cutoff_hz)), cutoff_hz)


def mount_filter(x: np.ndarray, fs: float, f_m: float, z_m: float, f_c: float
                 ) -> np.ndarray:
    """The platen's acceleration `x` as an accelerometer on a mount reads it (`mount_ba`);
    the mount's resonance decays over 1/(ζ_m ω_m), so the padding counts its periods by
    the damping too."""
    slowest = min(f_m * max(z_m, 1e-3) * 2 * np.pi / 2.6, f_c)
    return analog_filter(x, fs, mount_ba(float(f_m), float(z_m), float(f_c)), slowest)
