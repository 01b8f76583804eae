"""valve_flow_nonlinearity: turbulent orifice flow through the servovalve,
q ∝ x_sp √(P_s - sign(x_sp) P_L) (app. C, eq C.14): the flow gain, and so the loop gain,
falls with the load pressure, so the response depends on the amplitude. Normalised so
that the no-load gain is the linear one (Table B.5's k_t)."""

from __future__ import annotations

from vtable import units
from vtable.effects.base import Effect, Param
from vtable.params import presets


class ValveFlowNonlinearity(Effect):
    name = "valve_flow_nonlinearity"
    physics = ("turbulent orifice flow q ∝ x_sp √(P_s - sign(x_sp) P_L): the loop gain falls "
               "with load")
    section = "app. C (eq C.14)"
    signature = ("amplitude dependence: larger spans see a lower, more lagging x_t/x_c, most "
                 "at high frequency where the load pressure is large")
    params = (Param("supply_pressure", "psi",
                    lambda: units.from_si(presets.eerc_table().geometry.supply_pressure, "psi"),
                    300.0, 6000.0, log=True, source="§2.2: 3000 psi supply"),)

    def apply(self, m, p):
        m.set_servo(supply_pressure=p["supply_pressure"])


EFFECT = ValveFlowNonlinearity()
