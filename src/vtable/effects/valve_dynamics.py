"""valve_dynamics: the servovalve does not respond instantly (§6.2, app. C): the valve
flow q_v follows the commanded flow q through a first-order spool lag τ,
τ q̇_v = q - q_v — a valve stage of the hydraulic element (linear). On a table that
declares its valve's time constant (its own `SPOOL_LAG`) the effect is a further lag in
series (`VALVE_LAG`)."""

from __future__ import annotations

from vtable.effects.base import Effect, Param
from vtable.hydraulics.stage import Stage


def spool_lag(q, z, p, dz):
    """The valve flow z[0] lagging the commanded flow q by τ = p.tau."""
    dz[0] = (q - z[0]) / p.tau
    return z[0]


SPOOL_LAG = Stage("spool_lag", "valve", spool_lag, ("tau",), states=1, linear=True,
                  state_units=("m3/s",))
#: the same law as the effect's own stage: a lag beyond a table's declared valve lag
#: (`SPOOL_LAG`, the table's own), in series with it
VALVE_LAG = Stage("valve_lag", "valve", spool_lag, ("tau",), states=1, linear=True,
                  state_units=("m3/s",))


class ValveDynamics(Effect):
    name = "valve_dynamics"
    physics = "the servovalve does not respond instantly: a first-order spool (flow) lag τ"
    section = "§6.2, app. C"
    signature = "extra phase lag growing with frequency; lower bandwidth"
    params = (Param("tau", "s", 0.002, 1e-4, 0.05, log=True, source="assumed"),)

    def apply(self, m, p):
        # on a table that declares its valve's lag (SPOOL_LAG, LNEC's 24.6 ms) this is a
        # further lag in series: what the declared valve does not hold
        m.add_stage(VALVE_LAG, tau=p["tau"])


EFFECT = ValveDynamics()
