"""Linear servo-hydraulic control of the EERC table (eqs 6.1-6.5, B.4-B.6).

Per actuator group (H1-H3 under the horizontal x and twist controllers, V1-V4 under the
vertical z, pitch and roll controllers) the DOF servo law of `vtable.hydraulics.law`
(written once there) with the Table B.5 / derived constants, as a linear controller the
simulator fuses. A group's law may carry linear stages (the RC high-pass of eq B.4 on the
ΔP feedback, a valve lag: `vtable.controllers.standard_controllers` gives the table's).
"""

from __future__ import annotations

import numpy as np

from vtable.controllers.base import DOFS, LinearController
from vtable.hydraulics.law import GROUP_DOFS, ServoLaw, dof_matrix, group_law
from vtable.params.virtual import VirtualTable

GROUPS = GROUP_DOFS
DIRECTION_GROUP = {d: kind for kind, dofs in GROUPS.items() for d in dofs}

__all__ = ["DIRECTION_GROUP", "GROUPS", "ServoController", "dof_matrix"]


class ServoController(LinearController):
    """Linear servovalve + oil column per actuator with the DOF controllers of `groups`."""

    def __init__(self, vt: VirtualTable, groups: tuple[str, ...] = ("horizontal", "vertical"),
                 laws: dict[str, ServoLaw] | None = None) -> None:
        self.vt = vt
        self.laws = {k: (laws or {}).get(k) or group_law(vt, k)
                     for k in ("horizontal", "vertical") if k in groups and vt.group(k)}
        self.actuators = tuple(a for law in self.laws.values() for a in law.actuators)
        # state order (see `bind`): every group's first states (one per actuator), then
        # every group's others
        ks = [len(law.actuators) for law in self.laws.values()]

        def ordered(per_law: list[tuple[str, ...]]) -> tuple[str, ...]:
            return tuple([s for n, k in zip(per_law, ks, strict=True) for s in n[:k]] +
                         [s for n, k in zip(per_law, ks, strict=True) for s in n[k:]])

        self.state_names = ordered([law.state_names() for law in self.laws.values()])
        self.state_units = ordered([law.state_units() for law in self.laws.values()])

    def bind(self, actuator_names: tuple[str, ...]) -> None:
        n = len(actuator_names)
        blocks = [(law, law.linear_blocks()) for law in self.laws.values()]
        nz = sum(b.A.shape[0] for _, b in blocks)
        na = len(self.actuators)
        A, Bs = np.zeros((nz, nz)), np.zeros((nz, 2 * n))
        Bc, C = np.zeros((nz, len(DOFS))), np.zeros((na, nz))
        # state order: every group's pressures, then every group's filtered DOFs
        pos = {}
        row_p, row_f = 0, na
        for law, b in blocks:
            k = len(law.actuators)
            nf = b.A.shape[0] - k
            pos[id(law)] = list(range(row_p, row_p + k)) + list(range(row_f, row_f + nf))
            row_p += k
            row_f += nf
        out = 0
        for law, b in blocks:
            idx = pos[id(law)]
            cols = [actuator_names.index(a) for a in law.actuators]
            A[np.ix_(idx, idx)] = b.A
            Bs[np.ix_(idx, cols)] = b.Bx
            Bs[np.ix_(idx, [n + c for c in cols])] = b.Bv
            Bc[np.ix_(idx, [DOFS.index(d) for d in law.dofs])] = b.Bc
            k = len(law.actuators)
            C[np.ix_(range(out, out + k), idx)] = b.C
            out += k
        self.A, self.Bs, self.Bc, self.C = A, Bs, Bc, C
        self.Ds = np.zeros((na, 2 * n))
        self.Dc = np.zeros((na, len(DOFS)))
        self.reset()
