"""Passive pitch stabilizers, hydraulically cross-connected in pairs (§8.3, Fig 2.2).

For a pair (a, b) the oil column resists only the antisymmetric motion:
F_a = -k (x_a - x_b)/2 - c (ẋ_a - ẋ_b)/2, F_b = -F_a, with the per-piston stiffness
F/Δx = 2β_e A²/V of eq 8.3 and damping from `VirtualTable.stabilizers`. Moving both
pistons together (heave) meets no resistance; pitch meets k_p = (F/Δx) d_p² (eq 8.4).
"""

from __future__ import annotations

import numpy as np

from vtable.controllers.base import LinearController
from vtable.params.virtual import VirtualTable


class PassiveStabilizers(LinearController):
    """The four stabilizers P1-P4 as a stateless linear element (pure D term)."""

    def __init__(self, vt: VirtualTable) -> None:
        self.stab = vt.stabilizers
        self.actuators = tuple(a for pair in self.stab.pairs for a in pair)
        self.state_names = ()

    def bind(self, actuator_names: tuple[str, ...]) -> None:
        n = len(actuator_names)
        na = len(self.actuators)
        Ds = np.zeros((na, 2 * n))
        k, c = self.stab.stiffness, self.stab.damping
        for p, (a, b) in enumerate(self.stab.pairs):
            ia, ib = actuator_names.index(a), actuator_names.index(b)
            for row, sign in ((2 * p, 1.0), (2 * p + 1, -1.0)):
                Ds[row, ia] += -sign * k / 2
                Ds[row, ib] += sign * k / 2
                Ds[row, n + ia] += -sign * c / 2
                Ds[row, n + ib] += sign * c / 2
        self.A = np.zeros((0, 0))
        self.Bs = np.zeros((0, 2 * n))
        self.Bc = np.zeros((0, 5))
        self.C = np.zeros((na, 0))
        self.Ds, self.Dc = Ds, np.zeros((na, 5))
        self.reset()
