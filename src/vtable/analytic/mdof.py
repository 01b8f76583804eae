"""An MDOF shear building (eq 4.5) on the hybrid table (eq 8.37 generalised).

Generalised coordinates q = [x_t, θ, x_s1..x_sn] (x_s relative to the rigid base
motion x_t + h_j θ); heights from the actuator line. Neglecting gravity, as the report:

  horizontal: (m_t + Σm) ẍ_t + Σmh θ̈ + Σ m ẍ_s = F_a
  rocking:    Σmh ẍ_t + (I + Σmh²) θ̈ + Σ mh ẍ_s + c_θ θ̇ + k_θ θ = 0
  structure:  M_s (r_t ẍ_t + r_θ θ̈ + ẍ_s) + C_s ẋ_s + K_s x_s = 0   (eq 4.5)

and the horizontal servo loop on x_f = F_a/m_t as in eq 8.11. With one storey this is
exactly eq 8.37. C_s is the building's classical damping (`analytic.structure.
building_matrices`): each fixed-base mode at its declared ratio, one for all, one per mode,
or Rayleigh's α M_s + β K_s.
"""

from __future__ import annotations

import numpy as np

from vtable.analytic.base import LinearModel
from vtable.analytic.servo import loop_row
from vtable.analytic.structure import building_matrices
from vtable.params.loops import OpenLoop, RockingSpring
from vtable.params.specimen import ShearBuilding


class MDOFHybrid(LinearModel):
    """Shear building on the hybrid table; input x_c.

    Outputs: x_t, theta, x_eff1 = x_t + h_e1 θ (eq 4.13 with eq 4.24), and per storey j
    (1-based) x_s{j} (relative) and x_st{j} (total = x_t + h_j θ + x_s{j}).
    """

    def __init__(self, open_loop: OpenLoop, table_mass: float, table_inertia: float,
                 rocking: RockingSpring, building: ShearBuilding, title: str = "") -> None:
        self.open_loop, self.building = open_loop, building
        Ms, Ks, Cs = building_matrices(building)
        m = np.diag(Ms)
        h = np.asarray(building.heights)
        n = building.n
        nq = n + 2
        M = np.zeros((nq, nq))
        M[0, 0] = table_mass + m.sum()
        M[0, 1] = M[1, 0] = m @ h
        M[1, 1] = table_inertia + m @ h**2
        M[0, 2:] = M[2:, 0] = m
        M[1, 2:] = M[2:, 1] = m * h
        M[2:, 2:] = Ms
        K = np.zeros((nq, nq))
        C = np.zeros((nq, nq))
        K[1, 1], C[1, 1] = rocking.k_theta, rocking.c_theta
        K[2:, 2:], C[2:, 2:] = Ks, Cs
        Minv = np.linalg.inv(M)
        ns = 2 * nq + 1
        A = np.zeros((ns, ns))
        A[:nq, nq:2 * nq] = np.eye(nq)
        A[nq:2 * nq, :nq] = -Minv @ K
        A[nq:2 * nq, nq:2 * nq] = -Minv @ C
        A[nq:2 * nq, -1] = Minv[:, 0] * table_mass
        B = np.zeros((ns, 1))
        A[-1, [0, nq, -1]], B[-1, 0] = loop_row(open_loop)
        e = np.eye(ns)
        he1 = float(m @ h**2 / (m @ h))  # eq 4.24
        self.effective_height = he1
        outputs = {"x_t": (e[0], None), "theta": (e[1], None), "x_eff1": (e[0] + he1 * e[1], None),
                   "a_t": (A[nq], None)}
        for j in range(n):
            outputs[f"x_s{j + 1}"] = (e[2 + j], None)
            outputs[f"x_st{j + 1}"] = (e[0] + h[j] * e[1] + e[2 + j], None)
        states = (["x_t", "theta"] + [f"x_s{j + 1}" for j in range(n)]
                  + ["v_t", "omega"] + [f"v_s{j + 1}" for j in range(n)] + ["x_f"])
        super().__init__(**self._build(A, B, states, ("x_c",), outputs,
                                       title=title or f"{n}-storey building on the hybrid table"))
