"""The measurement chain's anti-aliasing filter (report §2.3: 100 Hz analog low-pass
before sampling), applied the same way to the virtual table's and the reduced model's
response channels: the analog 4-pole Butterworth (order assumed) applied exactly in the
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
def _response(nfft: int, fs: float, cutoff_hz: float) -> np.ndarray:
    """The analog filter's response on the FFT's frequencies (read-only: shared)."""
    b, a = scipy.signal.butter(ORDER, 2 * np.pi * cutoff_hz, analog=True)
    w = 2 * np.pi * np.fft.rfftfreq(nfft, 1.0 / fs)
    _, H = scipy.signal.freqs(b, a, worN=w)
    H.flags.writeable = False
    return H


#: zero padding, in periods of the cut-off: the filter's slowest poles decay as
#: exp(-sin(π/8) ω_c t), to 1e-10 of their start in 9.6 periods
PAD_PERIODS = 10.0


def sensor_filter(x: np.ndarray, fs: float, cutoff_hz: float) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    n = len(x)
    nfft = scipy.fft.next_fast_len(n + max(64, int(np.ceil(PAD_PERIODS * fs / cutoff_hz))),
                                   real=True)
    H = _response(nfft, float(fs), float(cutoff_hz))
    return scipy.fft.irfft(scipy.fft.rfft(x, nfft) * H, nfft)[:n]
