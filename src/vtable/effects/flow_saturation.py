"""flow_saturation: the servovalves' rated flow (their maximum spool stroke) caps the
actuators' velocity (§2.2: 25 in/s horizontal; app. C): |q| ≤ A·v_max — a flow stage of
the hydraulic element."""

from __future__ import annotations

from vtable import units
from vtable.effects.base import Effect, Param
from vtable.hydraulics.stage import Stage


def flow_cap(q, P, p):
    """The valve flow clipped at ±p.max_flow."""
    return min(max(q, -p.max_flow), p.max_flow)


FLOW_CAP = Stage("rated_flow", "flow", flow_cap, ("max_flow",), extensive=("max_flow",))


class FlowSaturation(Effect):
    name = "flow_saturation"
    physics = "the servovalve's rated flow caps actuator velocity"
    section = "§2.2, app. C"
    signature = ("clipping when the command velocity exceeds the cap; large spans and "
                 "earthquakes only")
    params = (Param("v_max", "in/s", lambda t: (units.from_si(t.velocity_limit, "in/s")
                                                if t.velocity_limit is not None else 60.0),
                    1.0, 60.0, log=True, source="the table's horizontal velocity "
                    "limit (EERC: Table 2.2, 25 in/s; a table that declares none: the "
                    "range's top)"),)
    stages = (FLOW_CAP,)

    def apply(self, m, p):
        m.add_stage(FLOW_CAP, max_flow=p["v_max"] * m.table.piston_area)


EFFECT = FlowSaturation()
