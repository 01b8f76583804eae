"""Uni-directional table carrying a SDOF structure (report ch. 7, eq 7.7)."""

from __future__ import annotations

import numpy as np

from vtable.analytic.base import LinearModel
from vtable.analytic.servo import loop_row
from vtable.params.loops import TableSDOFParams

STATES = ("x_t", "v_t", "f_a", "x_st", "v_st")  # f_a = F_a/m_t


class TableSDOF(LinearModel):
    """Eq 7.7: states x_t, ẋ_t, F_a/m_t, x_s^t, ẋ_s^t; input x_c.

    Outputs: x_t, x_st (total structure), x_s = x_s^t - x_t (relative), a_t, a_st, f_a.
    """

    def __init__(self, p: TableSDOFParams, title: str = "") -> None:
        self.params = p
        ol, st = p.open_loop, p.structure
        ws, xs, u = st.omega_s, st.xi_s, st.u
        row, b = loop_row(ol)
        A = np.array([
            [0, 1, 0, 0, 0],
            [-ws**2 * u, -2 * xs * ws * u, 1, ws**2 * u, 2 * xs * ws * u],
            [*row, 0, 0],
            [0, 0, 0, 0, 1],
            [ws**2, 2 * xs * ws, 0, -ws**2, -2 * xs * ws],
        ])
        B = np.array([[0], [0], [b], [0], [0]])
        e = np.eye(5)
        outputs = {"x_t": (e[0], None), "x_st": (e[3], None), "x_s": (e[3] - e[0], None),
                   "a_t": (A[1], None), "a_st": (A[4], None), "f_a": (e[2], None)}
        super().__init__(**self._build(A, B, STATES, ("x_c",), outputs,
                                       title=title or p.title or "table + SDOF (eq 7.7)"))


def tf_7_9(p: TableSDOFParams) -> tuple[np.ndarray, np.ndarray]:
    """Numerator and denominator of H_tc = x_t/x_c, eq 7.9 (highest power first)."""
    ol, st = p.open_loop, p.structure
    return coefficients_7_9(ol.omega_o, ol.xi_o, ol.k_o, st.omega_s, st.xi_s, st.u)


def coefficients_7_9(wo, xo, ko, ws, xs, u) -> tuple[np.ndarray, np.ndarray]:
    """Eq 7.9's numerator k_o (s² + 2ξ_sω_s s + ω_s²) and denominator a5 s⁵ + ... + a0
    (highest power first) from ω_o, ξ_o, k_o, ω_s, ξ_s and u = m_s/m_t.

    The printed a2 has ξ_s where ξ_o belongs; derived from eqs 7.3, 7.6 and 7.8:
    a2 = 2(1+u) ω_s² ξ_o/ω_o + 2 ξ_s ω_s + k_o.
    """
    r = ws / wo
    a0 = ko * ws**2
    a1 = ws**2 + 2 * ws * xs * ko
    a2 = 2 * (1 + u) * ws**2 * xo / wo + 2 * xs * ws + ko
    a3 = r**2 * (1 + u) + 4 * r * xo * xs * (1 + u) + 1
    a4 = 2 * ((1 + u) * r * xs + xo) / wo
    a5 = 1 / wo**2
    num = ko * np.array([1.0, 2 * xs * ws, ws**2])
    return num, np.array([a5, a4, a3, a2, a1, a0])


def hurwitz_7_10(den: np.ndarray) -> tuple[float, float, float]:
    """c1, c2, c3 of eq 7.10 for a5 s⁵ + ... + a0 (all > 0 with a_i > 0 for stability)."""
    a5, a4, a3, a2, a1, a0 = den
    c1 = a3 * a4 - a2 * a5
    c2 = a1 * c1 - a4 * (a1 * a4 - a0 * a5)
    c3 = -a0 * a3 * c1 + a0 * a5 * (a1 * a4 - a0 * a5) + a1 * c2
    return c1, c2, c3
