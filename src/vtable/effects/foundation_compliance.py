"""foundation_compliance: the reaction mass and its foundation are not rigid (§1.2, Rea):
the horizontal actuators push against the reaction block (1580 kips, §2.2) on a
horizontal spring and dashpot of natural frequency f_f and damping ratio ξ_f (the
reaction mass is the run's table's, `m.table.foundation_mass`)."""

from __future__ import annotations

import math

from vtable.effects.base import Effect, Param

#: why ξ_f's prior is wide (`Param.spread`): a reaction's damping depends on what it is
_XI_F = ("varies over decades from table to table: about 0.01 for a steel reaction frame "
         "bolted to a strong floor, 0.1-0.3 for a concrete block radiating into soil")


class FoundationCompliance(Effect):
    name = "foundation_compliance"
    physics = ("the reaction mass (1580 kips, §2.2) moves on a horizontal spring and "
               "dashpot, so the actuators push against a compliant base")
    section = "§1.2 (Rea)"
    signature = ("absolute accelerations differ from the actuator displacements' at low "
                 "frequency; a foundation resonance")
    params = (Param("f_f", "Hz", 10.0, 1.0, 60.0, log=True, source="assumed"),
              Param("xi_f", "1", 0.1, 0.005, 0.9, log=True, source="assumed",
                    spread=10.0, doc=_XI_F))

    def apply(self, m, p):
        mass = m.table.foundation_mass
        w = 2 * math.pi * p["f_f"]
        m.add_reaction_mass("foundation", mass, mass * w * w, 2 * p["xi_f"] * w * mass)


EFFECT = FoundationCompliance()
