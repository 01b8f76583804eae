"""Bare table with the RC high-pass filter on the ΔP feedback (App. B, eq B.7)."""

from __future__ import annotations

import numpy as np

from vtable.analytic.base import LinearModel
from vtable.params.table import ServoConstants


class RCFilterServo(LinearModel):
    """Eqs B.4-B.7 per actuator, states P_L, P_f, ẋ_t, x_t; input x_c.

    (V/4β) Ṗ_L = -k_ct P_L - (A + k_t k_v) ẋ_t + k_t (x_c - x_t - k_p P_f)   (B.6)
    Ṗ_f = -P_f/RC + Ṗ_L   (B.4),   ẍ_t = A P_L / m   (B.5)
    (B.7 as printed keeps k_v = 0 and drops the last two entries of its input vector.)
    """

    STATES = ("p_l", "p_f", "v_t", "x_t")

    def __init__(self, c: ServoConstants, title: str = "") -> None:
        self.constants = c
        g = 4 * c.beta / c.volume
        row1 = g * np.array([-c.k_ct, -c.k_t * c.k_p, -(c.area + c.k_t * c.k_v), -c.k_t])
        A = np.array([row1, row1 - [0, 1 / c.rc, 0, 0],
                      [c.area / c.mass, 0, 0, 0], [0, 0, 1, 0]])
        B = np.array([[g * c.k_t], [g * c.k_t], [0], [0]])
        e = np.eye(4)
        outputs = {"x_t": (e[3], None), "v_t": (e[2], None), "a_t": (A[2], None),
                   "p_l": (e[0], None), "force": (c.area * e[0], None)}
        super().__init__(**self._build(A, B, self.STATES, ("x_c",), outputs,
                                       title=title or "bare table with RC filter (eq B.7)"))
