"""The two models §9.4 adds to the report's table models for the interaction study, each
driven by the table command x_c and reporting the structure's deformation x_s: the
specimen on an ideal table (fixed base) and the rocking model (the table follows x_c and
only rocks)."""

from __future__ import annotations

import numpy as np

from vtable.analytic.base import LinearModel
from vtable.analytic.pitch import structure_rows
from vtable.params.loops import StructureRatios

TWO_PI = 2 * np.pi


def _displacement_driven(A: np.ndarray, b: np.ndarray, positions: dict[str, np.ndarray]
                         ) -> tuple[np.ndarray, dict[str, tuple]]:
    """ż = A z + b ẍ_c rewritten for input x_c: w = z - A b x_c - b ẋ_c obeys
    ẇ = A w + A² b x_c, and a position output c z (c b = 0) is c w + (c A b) x_c."""
    Ab = A @ b
    return (A @ Ab).reshape(-1, 1), {k: (c, [c @ Ab]) for k, c in positions.items()}


class FixedBaseModel(LinearModel):
    """The specimen alone on an ideal table: ẍ_s + 2ξ_sω_s ẋ_s + ω_s² x_s = -ẍ_c."""

    def __init__(self, st: StructureRatios) -> None:
        ws = st.omega_s
        A = np.array([[0.0, 1.0], [-ws**2, -2 * st.xi_s * ws]])
        B, out = _displacement_driven(A, np.array([0.0, -1.0]), {"x_s": np.array([1.0, 0])})
        super().__init__(**self._build(A, B, ("x_s", "v_s"), ("x_c",), out,
                                       title="fixed-base structure"))


class RockingModel(LinearModel):
    """§9.4 rocking model (Fig 5.2): the table follows x_c horizontally and only rocks on
    the spring and dashpot ω_θ, ξ_θ. Rows of eqs 8.13-8.15 with x_t prescribed, written
    in y = x_s^t - x_t: states y, x_r = θh, ẏ, ẋ_r; deformation x_s = y - x_r."""

    def __init__(self, st: StructureRatios, f_theta: float, xi_theta: float) -> None:
        R = structure_rows(st, TWO_PI * f_theta, xi_theta)  # over [x_t,x_r,x_st,v_t,v_r,v_st]
        # substitute x_st = y + x_t: the x_t terms cancel; ÿ = ẍ_st - ẍ_c
        A = np.zeros((4, 4))
        A[0:2, 2:4] = np.eye(2)
        A[2] = [R[2, 2], R[2, 1], R[2, 5], R[2, 4]]
        A[3] = [R[1, 2], R[1, 1], R[1, 5], R[1, 4]]
        B, out = _displacement_driven(A, np.array([0.0, 0, -1, 0]),
                                      {"x_s": np.array([1.0, -1, 0, 0]),
                                       "theta_h": np.array([0.0, 1, 0, 0])})
        super().__init__(**self._build(A, B, ("y", "x_r", "v_y", "v_r"), ("x_c",), out,
                                       title="rocking model"))
