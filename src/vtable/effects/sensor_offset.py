"""sensor_offset: the table accelerometer's zero is not at zero.

A platen that starts and ends a run at rest has a mean acceleration of (v_end − v_start)/T,
zero to within its noise; a table acceleration channel whose mean is not is read through a
zero offset b (the conditioner's zero, or the sensor's drift since it was zeroed): the
channel reads a + b. Both models add b to that channel (`avg_hacc`, the run format's table
horizontal acceleration) at their simulation rate; no other channel sees it (the servo loop
holds the displacement transducer's reading at the command, so its zero moves the platen,
not the reading). One offset for the campaign's runs: runs zeroed apart are best diagnosed
apart, or converted with their zero removed.
"""

from __future__ import annotations

import statistics

import numpy as np

from vtable.effects.base import Effect, Param
from vtable.units import G

#: the channel the offset is read on (measurement-format.md)
CHANNELS = ("avg_hacc",)

#: below this share of its RMS a run's mean acceleration is not an offset worth a fit: it
#: adds less than 0.02² to the error's square
NEGLIGIBLE = 0.02


def _means(campaign) -> list[tuple[float, float]]:
    """(mean, RMS) of every run's table acceleration over the whole run (SI)."""
    out = []
    for run in campaign.runs:
        if "avg_hacc" not in run.channels:
            continue
        a = np.asarray(run.channels["avg_hacc"])
        a = a[np.isfinite(a)]
        if a.size:
            out.append((float(np.mean(a)), float(np.sqrt(np.mean(a**2)))))
    return out


class SensorOffset(Effect):
    name = "sensor_offset"
    physics = ("the table accelerometer's zero offset (its conditioner's zero, or drift "
               "since zeroing): the acceleration channel reads the platen's acceleration plus "
               "a constant")
    section = "§2.3 (the measurement chain)"
    signature = ("the table acceleration's mean over a run is not zero (a platen at rest at "
                 "both ends has a mean acceleration of zero); a constant error on that channel "
                 "alone, at every amplitude")
    params = (Param("offset", "g", 0.0, -0.1, 0.1, source="none: a zeroed sensor reads 0",
                    doc="what the acceleration channel reads with the platen at rest"),)

    def unsupported(self, campaign):
        """Not tried where no run's table acceleration has a mean of `NEGLIGIBLE` of its
        RMS: the runs show no offset to fit."""
        if any(abs(m) > NEGLIGIBLE * r for m, r in _means(campaign)):
            return None
        return (f"no run's table acceleration has a mean of {NEGLIGIBLE:.0%} of its RMS (or "
                "no run has one): the runs show no offset")

    def evidence(self, campaign):
        """The median over the runs of the table acceleration's mean."""
        means = [m for m, _ in _means(campaign)]
        if not means:
            return None
        return ({"offset": statistics.median(means) / G},
                "the mean of the runs' table acceleration (a platen at rest at both ends has "
                "none)")

    def apply(self, m, p):
        b = p["offset"]  # SI (m/s²), as every parameter reaches `apply`
        m.add_output_filter(lambda x, fs: x + b, CHANNELS)


EFFECT = SensorOffset()
