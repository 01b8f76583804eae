"""The measurement chain's anti-aliasing filter (report §2.3: 100 Hz analog low-pass
before sampling), applied the same way to the virtual table's and the reduced model's
channels: a 4-pole Butterworth (assumed order) discretized by the bilinear transform at
the simulation rate, before decimation to the sampling rate."""

from __future__ import annotations

import numpy as np
import scipy.signal

ORDER = 4


def sensor_filter(x: np.ndarray, fs: float, cutoff_hz: float) -> np.ndarray:
    sos = scipy.signal.butter(ORDER, cutoff_hz, fs=fs, output="sos")
    return scipy.signal.sosfilt(sos, np.asarray(x, dtype=float))
