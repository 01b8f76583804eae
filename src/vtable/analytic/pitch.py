"""Tables that pitch: two-directional with a pitch actuator (eq 8.16) and the hybrid
model with an equivalent rocking spring and dashpot (eq 8.37). Report ch. 8."""

from __future__ import annotations

import numpy as np

from vtable.analytic.base import LinearModel
from vtable.analytic.closed_forms import pitch_loop_from_springs, stabilizer_rocking
from vtable.analytic.servo import loop_row
from vtable.params import presets
from vtable.params.loops import (
    HybridParams,
    OpenLoop,
    RockingSpring,
    StructureRatios,
    TwoDirectionalParams,
    spring_frequency,
)

TWO_PI = 2 * np.pi


def structure_rows(st: StructureRatios, w_theta: float, xi_theta: float) -> np.ndarray:
    """Rows 4-6 (ẍ_t, ẍ_r, ẍ_s^t) of eqs 8.13-8.15 over [x_t, x_r, x_st, v_t, v_r, v_st]."""
    ws, xs, u, v = st.omega_s, st.xi_s, st.u, st.v
    a, c, e = 2 * xs * ws * u, 2 * xs * ws * v, 2 * xs * ws
    b = -ws**2 * v - w_theta**2
    d = 2 * xs * ws * v + 2 * xi_theta * w_theta
    return np.array([
        [-ws**2 * u, -ws**2 * u, ws**2 * u, -a, -a, a],
        [-ws**2 * v, b, ws**2 * v, -c, -d, c],
        [ws**2, ws**2, -ws**2, e, e, -e],
    ])


def _outputs(n: int, A: np.ndarray, height: float | None) -> dict[str, tuple]:
    e = np.eye(n)
    out = {"x_t": (e[0], None), "theta_h": (e[1], None), "x_eff": (e[0] + e[1], None),
           "x_st": (e[2], None), "x_s": (e[2] - e[0] - e[1], None),
           "a_t": (A[3], None), "a_eff": (A[3] + A[4], None), "a_st": (A[5], None),
           "x_f": (e[6], None)}
    if height:
        out["theta"] = (e[1] / height, None)
    return out


class HybridModel(LinearModel):
    """Eq 8.37: horizontal servo loop + rocking spring/dashpot (ω_θ, ξ_θ).

    States x_t, x_r = θh, x_s^t, ẋ_t, ẋ_r, ẋ_s^t, x_f = F_a/m_t; input x_c.
    Outputs x_t, theta_h, x_eff = x_t + θh, x_st, x_s (relative), accelerations, and θ
    when the height h is given (Table 9.1 gives only v = m_s h²/I).
    """

    STATES = ("x_t", "x_r", "x_st", "v_t", "v_r", "v_st", "x_f")

    def __init__(self, p: HybridParams, height: float | None = None, title: str = "") -> None:
        self.params, self.height = p, height
        ol = p.open_loop
        wt = TWO_PI * p.f_theta
        A = np.zeros((7, 7))
        A[0:3, 3:6] = np.eye(3)
        A[3:6, 0:6] = structure_rows(p.structure, wt, p.xi_theta)
        A[3, 6] = 1.0
        B = np.zeros((7, 1))
        A[6, [0, 3, 6]], B[6, 0] = loop_row(ol)
        super().__init__(**self._build(A, B, self.STATES, ("x_c",), _outputs(7, A, height),
                                       title=title or p.title or "hybrid model (eq 8.37)"))


class TwoDirectionalTable(LinearModel):
    """Eq 8.16: horizontal and pitch actuator loops, passive stabilizers (ω_p, ξ_p).

    States x_t, x_r, x_s^t, ẋ_t, ẋ_r, ẋ_s^t, x_f = F_a/m_t, x_m = M_r h/I;
    inputs x_c and θ_c.
    """

    STATES = ("x_t", "x_r", "x_st", "v_t", "v_r", "v_st", "x_f", "x_m")

    def __init__(self, p: TwoDirectionalParams, title: str = "") -> None:
        self.params = p
        ol, pl = p.open_loop, p.pitch_loop
        A = np.zeros((8, 8))
        A[0:3, 3:6] = np.eye(3)
        A[3:6, 0:6] = structure_rows(p.structure, TWO_PI * p.f_p, p.xi_p)
        A[3, 6] = 1.0
        A[4, 7] = 1.0
        B = np.zeros((8, 2))
        A[6, [0, 3, 6]], B[6, 0] = loop_row(ol)
        A[7, [1, 4, 7]], b = loop_row(pl)  # the pitch loop on x_r = θh, commanded θ_c h
        B[7, 1] = b * p.height
        outputs = _outputs(8, A, p.height)
        outputs["x_m"] = (np.eye(8)[7], None)
        super().__init__(**self._build(A, B, self.STATES, ("x_c", "theta_c"), outputs,
                                       title=title or p.title or "two-directional table (8.16)"))


def pitch_loop(f_r: float, inertia: float) -> OpenLoop:
    """The §8.6.2 pitch loop of open-loop frequency `f_r` (Hz) on a slab of pitch inertia
    `inertia` whose spring and dashpot at the coupled frequency are `presets.pitch_springs()`
    (eqs 8.28-8.29 inverted)."""
    sp = presets.pitch_springs()
    return pitch_loop_from_springs(sp.k_v, sp.c_v, sp.f_coupled, f_r, inertia)


def two_directional(f_r: float = 21.0) -> TwoDirectionalParams:
    """Eq 8.16 consistent with Table 8.1 at the coupled frequency (§8.6.2).

    The pitch loop (open-loop frequency `f_r` Hz, 13 or 21 in the report) is chosen so
    its spring and dashpot at 2.58 Hz are the vertical actuators' k_v, c_v (eqs 8.28-8.29
    inverted); the passive stabilizers carry k_p = k_θ - k_v and c_p = c_θ - c_v
    (eqs 8.32-8.33, `stabilizer_rocking`).
    """
    spec, m_t, inertia, part = presets.physical("table8_1")
    rock = part("rocking", RockingSpring)
    pitch = pitch_loop(f_r, inertia)
    k_p, c_p = stabilizer_rocking(rock.k_theta, rock.c_theta, inertia, pitch,
                                  presets.pitch_springs().f_coupled)
    f_p, xi_p = spring_frequency(k_p, c_p, inertia)
    return TwoDirectionalParams(
        open_loop=part("open_loop", OpenLoop), pitch_loop=pitch,
        structure=StructureRatios.from_physical(spec, m_t, inertia),
        f_p=f_p, xi_p=xi_p, height=spec.height,
        title=f"two-directional table, pitch loop f_r = {f_r:g} Hz (§8.6.2)",
        source="§8.6.2, Table 8.1")
