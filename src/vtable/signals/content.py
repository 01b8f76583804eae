"""Where a signal has content: the one rule the drive's amplification figures and the
reports' Bode plots share."""

from __future__ import annotations

#: a frequency line holds content where the signal's power spectral density is within this
#: many dB of its peak. Beyond it a ratio to the signal divides noise by almost nothing (an
#: earthquake's displacement falls steeply with frequency and stays coherent well below its
#: peak; at 60 dB a band-limited random command's leakage beyond its band passed)
CONTENT_DB = 40.0
#: the same as a fraction of the peak power
CONTENT_POWER = 10 ** (-CONTENT_DB / 10)
