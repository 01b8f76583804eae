"""valve_flow_nonlinearity: turbulent orifice flow through the servovalve,
q ∝ x_sp √(P_s - sign(x_sp) P_L) (app. C, eq C.14): the flow gain, and so the loop gain,
falls with the load pressure, so the response depends on the amplitude. Normalised so
that the no-load gain is the linear one (Table B.5's k_t) — a flow stage of the hydraulic
element, after the rated-flow cap."""

from __future__ import annotations

import math

from vtable import units
from vtable.effects.base import Effect, Param
from vtable.hydraulics.stage import Stage


def orifice(q, P, p):
    """q √(1 - sign(q) P/P_s) (eq C.14), no flow against more than the supply pressure."""
    s = 1.0 - (P if q >= 0 else -P) / p.supply_pressure
    return q * math.sqrt(s) if s > 0 else 0.0


ORIFICE = Stage("orifice", "flow", orifice, ("supply_pressure",), order=1.0)


class ValveFlowNonlinearity(Effect):
    name = "valve_flow_nonlinearity"
    physics = ("turbulent orifice flow q ∝ x_sp √(P_s - sign(x_sp) P_L): the loop gain falls "
               "with load")
    section = "app. C (eq C.14)"
    signature = ("amplitude dependence: larger spans see a lower, more lagging x_t/x_c, most "
                 "at high frequency where the load pressure is large")
    params = (Param("supply_pressure", "psi",
                    lambda t: units.from_si(t.supply_pressure, "psi"), 300.0, 6000.0,
                    log=True, source="the table's supply pressure (EERC: §2.2, 3000 psi)"),)
    stages = (ORIFICE,)

    def apply(self, m, p):
        m.add_stage(ORIFICE, supply_pressure=p["supply_pressure"])


EFFECT = ValveFlowNonlinearity()
