"""sensor_mount: the table's accelerometer on a mount that is not rigid, behind its signal
conditioner's low-pass.

The accelerometer is a small mass on a mount of one resonance (f_m, ζ_m) on the platen,
read through the conditioner's second-order low-pass (f_c): the table acceleration channel
reads the platen's acceleration through R(s) (`vtable.effects.sensor.mount_ba`; the law
`vtable.diagnose.sensors` fits to a run's ẍ/s²x when the two table channels disagree),
and no other channel does: the displacement transducer, the load cells and the specimen's
sensors see the platen directly. Both models apply R exactly in the frequency domain to
that channel (`avg_hacc`, the run format's table horizontal acceleration) at their
simulation rate, before decimation, as they apply the anti-aliasing filter (§2.3).
"""

from __future__ import annotations

import statistics

from vtable.effects.base import Effect, Param
from vtable.effects.sensor import mount_filter

#: the channel the mount stands between the platen and (measurement-format.md)
CHANNELS = ("avg_hacc",)


class SensorMount(Effect):
    name = "sensor_mount"
    physics = ("the table accelerometer on a mount of one resonance (f_m, ζ_m) behind its "
               "conditioner's second-order low-pass (f_c); the other channels see the platen")
    section = "§2.3 (the measurement chain)"
    signature = ("the table acceleration alone departs from s² times the table displacement: "
                 "a peak near f_m and a roll-off above it; displacement, force and the "
                 "specimen's channels are unchanged")
    params = (Param("f_m", "Hz", 60.0, 5.0, 200.0, log=True, source="assumed",
                    doc="the mount's resonance"),
              Param("zeta_m", "1", 0.05, 0.005, 1.0, log=True, source="assumed",
                    doc="its damping ratio"),
              Param("f_c", "Hz", 100.0, 5.0, 400.0, log=True, source="§2.3 (100 Hz analog)",
                    doc="the conditioner's low-pass (second-order Butterworth)"))

    def unsupported(self, campaign):
        """Not tried where every run's table acceleration is the second derivative of its
        table displacement (`vtable.diagnose.sensors`: no run in `campaign.sensors`, the
        runs whose two table channels disagree): the runs show no mount to fit."""
        if campaign.sensors:
            return None
        return ("no run's table acceleration departs from the second derivative of its table "
                "displacement (or no run has both): the runs show no mount")

    def evidence(self, campaign):
        """The mount `vtable.diagnose.sensors` fits to the runs' ẍ/s²x where their table
        channels disagree: the median over those runs."""
        fits = [c.mount for c in campaign.sensors if c.mount is not None]
        if not fits:
            return None
        values = {k: statistics.median(f[i] for f in fits)
                  for i, k in enumerate(("f_m", "zeta_m", "f_c"))}
        return values, "fitted to the runs' ẍ/s²x (the sensor check)"

    def apply(self, m, p):
        f_m, z_m, f_c = p["f_m"], p["zeta_m"], p["f_c"]
        m.add_output_filter(lambda x, fs: mount_filter(x, fs, f_m, z_m, f_c), CHANNELS)


EFFECT = SensorMount()
