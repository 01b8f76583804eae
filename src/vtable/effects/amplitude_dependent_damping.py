"""amplitude_dependent_damping: the specimen's damping grows with its response amplitude
(friction between the stacked masses; §3.3.1.2, Fig. 3.2), as a quadratic damper
c₂|ẋ_s|ẋ_s on each storey: at drift amplitude a its equivalent viscous coefficient is
8c₂ωa/(3π), so ξ_eq = ξ + γa needs c₂ = 3πmγ/4 (m: the SDOF mass, or a building's top
storey mass)."""

from __future__ import annotations

import math

from vtable.effects.base import Effect, Param
from vtable.params.specimen import SDOFSpecimen, ShearBuilding


class AmplitudeDependentDamping(Effect):
    name = "amplitude_dependent_damping"
    physics = ("the specimen's damping grows with its response amplitude (friction between "
               "the stacked masses): a quadratic damper c₂|ẋ_s|ẋ_s, ξ rising γ per inch of drift")
    section = "§3.3.1.2, Fig. 3.2"
    signature = ("structure channels: the resonance is damped more in the large spans than "
                 "the small ones")
    params = (Param("gamma", "1/in", 0.01, 1e-4, 0.5, log=True, source="assumed"),)

    def apply(self, m, p):
        spec = m.specimen
        if isinstance(spec, SDOFSpecimen):
            mass = spec.mass
        elif isinstance(spec, ShearBuilding):
            mass = float(spec.masses[-1])
        else:
            return  # no storey to damp
        m.add_storey_quadratic_damper(3 * math.pi * mass * p["gamma"] / 4)


EFFECT = AmplitudeDependentDamping()
