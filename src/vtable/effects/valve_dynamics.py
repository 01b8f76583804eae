"""valve_dynamics: the servovalve does not respond instantly (§6.2, app. C): the valve
flow follows the commanded flow through a first-order spool lag τ."""

from __future__ import annotations

from vtable.effects.base import Effect, Param


class ValveDynamics(Effect):
    name = "valve_dynamics"
    physics = "the servovalve does not respond instantly: a first-order spool (flow) lag τ"
    section = "§6.2, app. C"
    signature = "extra phase lag growing with frequency; lower bandwidth"
    params = (Param("tau", "s", 0.002, 1e-4, 0.05, log=True, source="assumed"),)

    def apply(self, m, p):
        m.set_servo(spool_lag=p["tau"])


EFFECT = ValveDynamics()
