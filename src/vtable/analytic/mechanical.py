"""Mechanical model: rigid table on horizontal and rocking springs/dashpots (App. A)."""

from __future__ import annotations

import numpy as np

from vtable.analytic.base import LinearModel
from vtable.params.loops import MechanicalParams

TWO_PI = 2 * np.pi


def a13_matrices(p: MechanicalParams) -> tuple[np.ndarray, np.ndarray]:
    """A and b of eq A.13 over [ẋ_s^r, ẋ_t^r, ẋ_r, x_s^r, x_t^r, x_r] with input ẍ_c."""
    st = p.structure
    ws, xs, u, v = st.omega_s, st.xi_s, st.u, st.v
    wh, xh = TWO_PI * p.f_h, p.xi_h
    wr, xr = TWO_PI * p.f_theta, p.xi_theta
    s = 1 + u + v
    A = np.array([
        [-2 * xs * ws * s, 2 * xh * wh, 2 * xr * wr, -ws**2 * s, wh**2, wr**2],
        [2 * xs * ws * u, -2 * xh * wh, 0, ws**2 * u, -wh**2, 0],
        [2 * xs * ws * v, 0, -2 * xr * wr, ws**2 * v, 0, -wr**2],
        [1, 0, 0, 0, 0, 0],
        [0, 1, 0, 0, 0, 0],
        [0, 0, 1, 0, 0, 0],
    ])
    b = np.array([0.0, -1.0, 0.0, 0.0, 0.0, 0.0])
    return A, b


class MechanicalModel(LinearModel):
    """Eq A.13 driven by the command displacement x_c instead of ẍ_c.

    With z the A.13 state, w = z - A b x_c - b ẋ_c obeys ẇ = A w + A² b x_c, so the
    system is proper in x_c; positions are read from w (x_t = x_t^r + x_c = w₅ since
    (A b)₅ = -1). Same A, same eigenvalues as eq A.13.
    """

    STATES = ("w_vs", "w_vt", "w_vr", "x_s", "w_xt", "x_r")

    def __init__(self, p: MechanicalParams, height: float | None = None, title: str = "") -> None:
        self.params, self.height = p, height
        A, b = a13_matrices(p)
        B = (A @ A @ b).reshape(6, 1)
        e = np.eye(6)
        outputs = {"x_t": (e[4], None), "theta_h": (e[5], None), "x_eff": (e[4] + e[5], None),
                   "x_s": (e[3], None), "x_st": (e[3] + e[4] + e[5], None)}
        if height:
            outputs["theta"] = (e[5] / height, None)
        super().__init__(**self._build(A, B, self.STATES, ("x_c",), outputs,
                                       title=title or p.title or "mechanical model (eq A.13)"))
