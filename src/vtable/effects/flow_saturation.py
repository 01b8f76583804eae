"""flow_saturation: the servovalves' rated flow (their maximum spool stroke) caps the
actuators' velocity (§2.2: 25 in/s horizontal; app. C): |q| ≤ A·v_max."""

from __future__ import annotations

from vtable import units
from vtable.effects.base import Effect, Param
from vtable.params import presets


class FlowSaturation(Effect):
    name = "flow_saturation"
    physics = "the servovalve's rated flow caps actuator velocity"
    section = "§2.2, app. C"
    signature = ("clipping when the command velocity exceeds the cap; large spans and "
                 "earthquakes only")
    params = (Param("v_max", "in/s",
                    lambda: units.from_si(presets.eerc_table().rated_velocity(), "in/s"),
                    1.0, 60.0, log=True, source="Table 2.2: 25 in/s horizontal"),)

    def apply(self, m, p):
        m.set_servo(max_velocity=p["v_max"])


EFFECT = FlowSaturation()
