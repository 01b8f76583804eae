"""valve_dynamics: the servovalve does not respond instantly (§6.2, app. C): the valve
flow q_v follows the commanded flow q through a first-order spool lag τ,
τ q̇_v = q - q_v — a valve stage of the hydraulic element (linear). On a table that
declares its valve's time constant (its own `SPOOL_LAG`) the effect is a further lag in
series (`VALVE_LAG`); both laws are `vtable.hydraulics.table_stages`'."""

from __future__ import annotations

from vtable.effects.base import Effect, Param
from vtable.hydraulics.table_stages import VALVE_LAG


class ValveDynamics(Effect):
    name = "valve_dynamics"
    physics = "the servovalve does not respond instantly: a first-order spool (flow) lag τ"
    section = "§6.2, app. C"
    signature = "extra phase lag growing with frequency; lower bandwidth"
    params = (Param("tau", "s", 0.002, 1e-4, 0.05, log=True, source="assumed"),)
    stages = (VALVE_LAG,)

    def apply(self, m, p):
        # on a table that declares its valve's lag (SPOOL_LAG, LNEC's 24.6 ms) this is a
        # further lag in series: what the declared valve does not hold
        m.add_stage(VALVE_LAG, tau=p["tau"])


EFFECT = ValveDynamics()
