"""The bare uni-directional table: a 3rd-order servo loop (report ch. 6).

Open-loop parameters from physical constants (eq 6.14 without, eq 6.16 with feedback)
and back; the closed loop in state form (eq 6.18); the Routh-Hurwitz conditions
(eq 6.11, 6.17b).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from vtable.analytic.base import LinearModel
from vtable.errors import VtableError
from vtable.params.loops import OpenLoop
from vtable.params.table import ServoConstants

TWO_PI = 2 * math.pi


def open_loop_from_servo(c: ServoConstants, feedback: bool = True) -> OpenLoop:
    """(f_o, ξ_o, k_o) from physical constants.

    With feedback (eq 6.16): k_o = k/(k k_v + A), ω_o² = 4βA(k k_v + A)/(mV),
    ξ_o = m ω_o (k k_f + k_c) / (2(k k_v + A)), with k = k_t, k_f = k_p/A, k_c = k_ct/A.
    Without feedback (eq 6.14, k_v = k_f = 0): k̂_o = k_t/A, ω̂_o² = 4βA²/(mV),
    ξ̂_o = m k_c ω̂_o/(2A).

    A viscous damping c of the mass (m ẍ = A P - c ẋ; the report's tables have none)
    generalises eq 6.16 with A_e = A + k k_v + c(k_ct + k k_p)/A in place of k k_v + A:
    ω_o² = 4βA A_e/(mV), 2ξ_o/ω_o = (m(k_ct + k k_p) + cV/4β)/(A A_e), k_o = k/A_e.
    """
    k, A = c.k_t, c.area
    k_v, k_p = (c.k_v, c.k_p) if feedback else (0.0, 0.0)
    damp = c.damping or 0.0
    A_e = A + k * k_v + damp * (c.k_ct + k * k_p) / A
    w = math.sqrt(4 * c.beta * A * A_e / (c.mass * c.volume))
    xi = w * (c.mass * (c.k_ct + k * k_p) + damp * c.volume / (4 * c.beta)) / (2 * A * A_e)
    return OpenLoop(f_o=w / TWO_PI, xi_o=xi, k_o=k / A_e,
                    source="eq 6.16" if feedback else "eq 6.14")


def servo_from_open_loop(ol: OpenLoop, template: ServoConstants) -> ServoConstants:
    """Invert eq 6.16: solve k_t, β and k_ct for (f_o, ξ_o, k_o), holding the template's
    A, V, m, k_p (hence k_f), k_v and damping c fixed.

    Without damping in closed form: k = k_o A/(1 - k_o k_v); β = ω_o² m V/(4A(k k_v + A));
    k_c = 2ξ_o (k k_v + A)/(m ω_o) - k k_f; k_ct = A k_c. With damping the same equations
    with A_e of `open_loop_from_servo`, solved by fixed-point iteration (c·k_ct/A ≪ A).
    """
    A, kv, kp, c, m, V = (template.area, template.k_v, template.k_p, template.damping or 0.0,
                          template.mass, template.volume)
    if ol.k_o * kv >= 1:
        raise VtableError(f"k_o·k_v = {ol.k_o * kv:g} >= 1: no positive k_t gives k_o = "
                          f"{ol.k_o:g} with this velocity feedback")
    w = ol.omega_o
    k_ct = 0.0
    for _ in range(50 if c else 1):
        extra = c * k_ct / A
        k = ol.k_o * (A + extra) / (1 - ol.k_o * (kv + c * kp / A))
        A_e = A + k * kv + c * (k_ct + k * kp) / A
        beta = w**2 * m * V / (4 * A * A_e)
        new = (2 * ol.xi_o * A * A_e / w - c * V / (4 * beta)) / m - k * kp
        if abs(new - k_ct) <= 1e-14 * max(abs(new), 1e-30):
            k_ct = new
            break
        k_ct = new
    if k_ct < 0:
        raise VtableError(f"ξ_o = {ol.xi_o:g} is below what the pressure feedback and the "
                          "damping alone give: the flow-pressure coefficient k_ct would be "
                          "negative")
    return dataclasses.replace(template, k_t=k, beta=beta, k_ct=k_ct)


def routh_conditions(c: ServoConstants) -> tuple[float, float, float]:
    """Left-hand sides of eq 6.11 (all > 0 for stability), in SI:
    k_t,  k_t k_f + k_c,  (k_t k_f + k_c)(k_t k_v + A) - k_t V/(4βA) · (1/m)·m.

    Eq 6.11c as printed omits m; from eq 6.9b's coefficients a1 a2 - a0 a3 > 0 it is
    m(k_t k_f + k_c)(k_t k_v + A) - k_t V m/(4βA) > 0, i.e. divided by m as returned.
    """
    k, A = c.k_t, c.area
    d = k * c.k_f + c.k_c
    return k, d, d * (k * c.k_v + A) - k * c.volume / (4 * c.beta * A)


class ServoLoop(LinearModel):
    """Closed-loop bare table, eq 6.18: states x_t, ẋ_t, ẍ_t; input x_c.

    H(s) = k_o / (s(s²/ω_o² + 2ξ_o s/ω_o + 1) + k_o)  (eq 6.15b).
    """

    def __init__(self, open_loop: OpenLoop, title: str = "") -> None:
        self.open_loop = open_loop
        w, xi, k = open_loop.omega_o, open_loop.xi_o, open_loop.k_o
        A = np.array([[0, 1, 0], [0, 0, 1], [-w**2 * k, -w**2, -2 * xi * w]])
        B = np.array([[0], [0], [w**2 * k]])
        eye = np.eye(3)
        outputs = {"x_t": (eye[0], None), "v_t": (eye[1], None), "a_t": (eye[2], None),
                   "error": (-eye[0], [1.0])}
        super().__init__(**self._build(A, B, ("x_t", "v_t", "a_t"), ("x_c",), outputs,
                                       title=title or open_loop.title or "bare table servo loop"))

    @classmethod
    def from_servo(cls, c: ServoConstants, title: str = "") -> ServoLoop:
        """From physical constants through eq 6.16."""
        return cls(open_loop_from_servo(c), title=title or "bare table (physical constants)")

    def open_loop_tf(self, f_hz) -> np.ndarray:
        """G(j2πf) of eq 6.13 (equal to H/(1-H), eq 6.21)."""
        ol = self.open_loop
        s = 1j * TWO_PI * np.asarray(f_hz, dtype=float)
        return ol.k_o / (s * (s**2 / ol.omega_o**2 + 2 * ol.xi_o * s / ol.omega_o + 1))
