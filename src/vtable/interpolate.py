"""Band-limited upsampling of a command onto a finer integration step: the one
interpolator the reduced model and the multibody table's simulator both use.

A control stage that reads the command's velocity and acceleration (feedforward) weighs an
image at f_s - f by (f_s/f)² over the command at f, and a step-wise (linear) interpolation
turns the command's velocity into a staircase at the command's rate: the images must be
far below the 55 dB of `scipy.signal.resample_poly`'s default filter. Issue 18: an
earthquake's 1 Hz content imaged at 199 Hz made a PID + acceleration feedforward model's
table acceleration 3.5 x its displacement's second derivative; the multibody table's
linear interpolation of a 1 kHz command doubled its ẍ_t difference from the reduced model
under velocity feedforward on a valve without lag.
"""

from __future__ import annotations

import functools

import numpy as np
import scipy.signal

#: the interpolator's stop-band attenuation (dB) and transition (fraction of the input's
#: Nyquist frequency below it): passes to 0.8 of the input's Nyquist frequency
INTERPOLATOR_DB, INTERPOLATOR_WIDTH = 120.0, 0.2


@functools.lru_cache(maxsize=16)
def interpolator(up: int) -> np.ndarray:
    """The anti-imaging filter of an upsampling by `up`: a Kaiser-windowed sinc passing the
    input's band to 0.8 of its Nyquist frequency and stopping INTERPOLATOR_DB from its
    Nyquist frequency on (`scipy.signal.kaiserord`), designed once per `up`; its polyphase
    branches have unit DC gain within 1e-6."""
    n, beta = scipy.signal.kaiserord(INTERPOLATOR_DB, INTERPOLATOR_WIDTH / up)
    n += 1 - n % 2  # odd: a linear-phase filter with a whole-sample delay
    h = scipy.signal.firwin(n, (1.0 - INTERPOLATOR_WIDTH / 2) / up, window=("kaiser", beta))
    h.flags.writeable = False
    return h


def upsample(x: np.ndarray, up: int) -> np.ndarray:
    """`x` (uniform samples) on a grid `up` times finer, from its first sample to its last
    ((len(x) - 1) up + 1 samples), band-limited (`interpolator`); the original samples
    are kept to the filter's accuracy."""
    x = np.asarray(x, dtype=float)
    if up == 1:
        return np.ascontiguousarray(x)
    # padded by the line through its ends: a record that does not start or end at rest
    # does not ring over the filter's half-length
    y = scipy.signal.resample_poly(x, up, 1, window=interpolator(up), padtype="line")
    return y[: (len(x) - 1) * up + 1]


_UPSAMPLED: dict[tuple[int, int, int], tuple[np.ndarray, np.ndarray]] = {}


def upsampled(x_c: np.ndarray, n: int, up: int) -> np.ndarray:
    """The command interpolated band-limited onto the integration step (`upsample`),
    kept for the last few command arrays (a fit drives the model by the same array
    hundreds of times; the array is held with its result, so its id stays its own)."""
    if up == 1:
        return np.ascontiguousarray(x_c, dtype=float)
    key = (id(x_c), n, up)
    hit = _UPSAMPLED.get(key)
    if hit is not None and hit[0] is x_c:
        return hit[1]
    xc = upsample(x_c, up)  # (n - 1) up + 1 samples
    xc.flags.writeable = False
    if len(_UPSAMPLED) >= 32:
        _UPSAMPLED.pop(next(iter(_UPSAMPLED)))
    _UPSAMPLED[key] = (x_c, xc)
    return xc
