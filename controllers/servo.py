"""Linear servo-hydraulic control of the EERC table (eqs 6.1-6.5, B.4-B.6).

Per actuator i (piston area A_i, oil volume V_i, Table B.5 / derived constants):

    (V_i/4β) Ṗ_i = k_t,i u_i - k_ct,i P_i - A_i ẋ_i          (eqs 6.2-6.3, B.6)
    u_i = Σ_d T_id g_d [ (q_c,d - q_d) - k_p,d P̄f_d - k_v,d q̇_d ]   (eqs 6.1, 6.4)
    F_i = A_i P_i

where the DOF controllers d (horizontal x and twist for H1-H3; vertical z, pitch and
roll for V1-V4) see the DOF displacement q = T⁺x and DOF pressure P̄ = T⁺P computed from
the actuators (T_id = displacement of actuator i per unit of DOF d), and P̄f is P̄ through
the RC high-pass filter (eq B.4) where enabled. g_d, k_p,d, k_v,d follow the Table 3.2
knobs through the Table B.1-B.4 factors (`VirtualTable.gain_scales`). For identical
actuators and symmetric motion each DOF loop reduces exactly to eq 6.5a with the mass
per actuator M_d/ΣT_id² (the 100 kips/3g of Table B.5 for x).
"""

from __future__ import annotations

import numpy as np

from vtable.controllers.base import DOFS, LinearController
from vtable.params.table import ServoConstants
from vtable.params.virtual import VirtualTable

GROUPS = {"horizontal": ("x", "twist"), "vertical": ("z", "pitch", "roll")}
DIRECTION_GROUP = {d: kind for kind, dofs in GROUPS.items() for d in dofs}
DIRECTION_OF = {"x": "horizontal", "twist": "twist", "z": "vertical", "pitch": "pitch",
                "roll": "roll"}


def dof_matrix(vt: VirtualTable, kind: str) -> tuple[tuple[str, ...], np.ndarray]:
    """Actuator names of a group and T (n_act x n_dof): extension per unit DOF motion.

    Small rotations about the pivot: twist ψ moves H_i (at y_i) by -y_i ψ along x; pitch θ
    moves V_i (at x_i) by -x_i θ up; roll φ moves V_i by +y_i φ up.
    """
    acts = vt.group(kind)
    names = tuple(a.name for a in acts)
    if kind == "horizontal":
        T = np.array([[1.0, -a.slab_point[1]] for a in acts])
    else:
        T = np.array([[1.0, a.slab_point[1], -a.slab_point[0]] for a in acts])
        T = T[:, [0, 2, 1]]  # columns z, pitch, roll
    return names, T


class ServoController(LinearController):
    """Linear servovalve + oil column per actuator with the five DOF controllers.

    `rc_filter` names the DOFs whose ΔP feedback passes the RC high-pass of eq B.4
    (Table B.5: RC = 0.01 s); by default the horizontal ones, as on the EERC table.
    """

    def __init__(self, vt: VirtualTable, rc_filter: tuple[str, ...] = ("x", "twist"),
                 groups: tuple[str, ...] = ("horizontal", "vertical")) -> None:
        self.vt = vt
        self.rc_filter = tuple(d for d in rc_filter if DIRECTION_GROUP[d] in groups)
        self.groups = {}
        acts: list[str] = []
        for kind, servo in (("horizontal", vt.horizontal_servo),
                            ("vertical", vt.vertical_servo)):
            if kind not in groups:
                continue
            names, T = dof_matrix(vt, kind)
            self.groups[kind] = (names, T, servo)
            acts += names
        self.actuators = tuple(acts)
        filt = [d for kind in self.groups for d in GROUPS[kind] if d in self.rc_filter]
        self.state_names = tuple([f"P_{a}" for a in self.actuators] + [f"Pf_{d}" for d in filt])

    def dof_gains(self, dof: str, servo: ServoConstants) -> tuple[float, float, float]:
        """(g, k_p, k_v) of a DOF: knob scales times the group's reference constants."""
        g, p, r = self.vt.gain_scales(DIRECTION_OF[dof])
        return g, servo.k_p * p, servo.k_v * r

    def bind(self, actuator_names: tuple[str, ...]) -> None:
        n = len(actuator_names)
        na = len(self.actuators)
        filt = [d for kind in self.groups for d in GROUPS[kind] if d in self.rc_filter]
        nz = na + len(filt)
        A = np.zeros((nz, nz))
        Bs = np.zeros((nz, 2 * n))
        Bc = np.zeros((nz, len(DOFS)))
        C = np.zeros((na, nz))
        row = 0
        for kind, (names, T, servo) in self.groups.items():
            cols = [actuator_names.index(a) for a in names]
            Tp = np.linalg.pinv(T)  # DOF from actuators
            k = len(names)
            rows = slice(row, row + k)
            rc = servo.rc
            # (V/4β) Ṗ = k_t u - k_ct P - A ẋ  ->  Ṗ = (4β/V)(...)
            c0 = 4 * servo.beta / servo.volume
            # u = T G [ (q_c - Tp x) - Kp Pf - Kv Tp ẋ ]
            for j, dof in enumerate(GROUPS[kind]):
                g, kp, kv = self.dof_gains(dof, servo)
                tj = T[:, j]
                ci = DOFS.index(dof)
                Bc[rows, ci] += c0 * servo.k_t * g * tj
                Bs[rows, cols] += -c0 * servo.k_t * g * np.outer(tj, Tp[j])
                Bs[rows, [n + c for c in cols]] += -c0 * servo.k_t * g * kv * np.outer(tj, Tp[j])
                if dof in self.rc_filter:
                    fi = na + filt.index(dof)
                    A[rows, fi] += -c0 * servo.k_t * g * kp * tj
                else:
                    A[rows, rows] += -c0 * servo.k_t * g * kp * np.outer(tj, Tp[j])
            A[rows, rows] += -c0 * servo.k_ct * np.eye(k)
            Bs[rows, [n + c for c in cols]] += -c0 * servo.area * np.eye(k)
            # RC filters: Ṗf = -Pf/RC + d/dt(Tp_j P)
            for j, dof in enumerate(GROUPS[kind]):
                if dof in self.rc_filter:
                    fi = na + filt.index(dof)
                    A[fi] += Tp[j] @ A[rows]
                    Bs[fi] += Tp[j] @ Bs[rows]
                    Bc[fi] += Tp[j] @ Bc[rows]
                    A[fi, fi] += -1.0 / rc
            C[rows, rows] = servo.area * np.eye(k)
            row += k
        self.A, self.Bs, self.Bc, self.C = A, Bs, Bc, C
        self.Ds = np.zeros((na, 2 * n))
        self.Dc = np.zeros((na, len(DOFS)))
        self.reset()
