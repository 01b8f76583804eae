"""sensor_filter: the measurement chain's anti-aliasing low-pass before sampling (§2.3:
100 Hz analog), a 4-pole Butterworth (order assumed) applied exactly in the frequency
domain to every measured response channel (`vtable.effects.sensor`)."""

from __future__ import annotations

from vtable.effects.base import Effect, Param
from vtable.effects.sensor import sensor_filter
from vtable.params import presets


class SensorFilter(Effect):
    name = "sensor_filter"
    physics = ("the measurement chain's anti-aliasing low-pass (4-pole Butterworth, 100 Hz, "
               "§2.3) before sampling")
    section = "§2.3"
    signature = ("every measured channel lags the command by a delay ≈ 2.6/(2π f_c); phase "
                 "error growing linearly with frequency")
    params = (Param("cutoff_hz", "Hz", presets.anti_alias_hz, 5.0, 400.0, log=True,
                    source="§2.3"),)

    def apply(self, m, p):
        fc = p["cutoff_hz"]
        m.add_output_filter(lambda x, fs: sensor_filter(x, fs, fc))


EFFECT = SensorFilter()
