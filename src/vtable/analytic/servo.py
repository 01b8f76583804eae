"""The bare uni-directional table: a 3rd-order servo loop (report ch. 6).

The servo law's row every closed-loop model shares (`loop_row`); open-loop parameters
from physical constants (eq 6.14 without, eq 6.16 with feedback) and back; the closed
loop in state form (eq 6.18); the Routh-Hurwitz conditions (eq 6.11, 6.17b).
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


def loop_row(ol: OpenLoop) -> tuple[np.ndarray, float]:
    """The servo law's row of every closed-loop model (eqs 6.5a, 6.18, 7.7, 8.11, 8.16).

    With x_f = F_a/m_t (ẍ_t on the bare table) the loop of eq 6.15 in state form is
    ẋ_f = -k_o ω_o² x - ω_o² ẋ - 2ξ_o ω_o x_f + k_o ω_o² x_c, so the bare table's
    x_t/x_c = k_o ω_o²/(s³ + 2ξ_o ω_o s² + ω_o² s + k_o ω_o²) (eq 6.15b).

    Returns
    -------
    row : ndarray
        Coefficients on (x, ẋ, x_f): (-k_o ω_o², -ω_o², -2ξ_o ω_o).
    b : float
        Coefficient on the command x_c: k_o ω_o².
    """
    w2 = ol.omega_o**2
    return np.array([-ol.k_o * w2, -w2, -2 * ol.xi_o * ol.omega_o]), ol.k_o * w2


def open_loop_from_servo(c: ServoConstants, feedback: bool = True) -> OpenLoop:
    """(f_o, ξ_o, k_o) from physical constants.

    With feedback (eq 6.16): k_o = k/(k k_v + A), ω_o² = 4βA(k k_v + A)/(mV),
    ξ_o = m ω_o (k k_f + k_c) / (2(k k_v + A)), with k = k_t, k_f = k_p/A, k_c = k_ct/A.
    Without feedback (eq 6.14, k_v = k_f = 0): k̂_o = k_t/A, ω̂_o² = 4βA²/(mV),
    ξ̂_o = m k_c ω̂_o/(2A).

    A viscous damping c of the mass (m ẍ = A P - c ẋ; the report's tables have none)
    generalises eq 6.16 with A_e = A + k k_v + c(k_ct + k k_p)/A in place of k k_v + A:
    ω_o² = 4βA A_e/(mV), 2ξ_o/ω_o = (m(k_ct + k k_p) + cV/4β)/(A A_e), k_o = k/A_e.
    `servo_from_open_loop` is the inverse.
    """
    k, A = c.k_t, c.area
    k_v, k_p = (c.k_v, c.k_p) if feedback else (0.0, 0.0)
    damp = c.damping or 0.0
    A_e = A + k * k_v + damp * (c.k_ct + k * k_p) / A
    w = math.sqrt(4 * c.beta * A * A_e / (c.mass * c.volume))
    xi = w * (c.mass * (c.k_ct + k * k_p) + damp * c.volume / (4 * c.beta)) / (2 * A * A_e)
    return OpenLoop(f_o=w / TWO_PI, xi_o=xi, k_o=k / A_e,
                    source="eq 6.16" if feedback else "eq 6.14")


#: the constants `servo_from_open_loop` may solve eq 6.16 for (the rest held)
UNKNOWNS = {"leakage": ("k_t", "beta", "k_ct"), "feedback": ("k_t", "volume", "k_p")}


def servo_from_open_loop(ol: OpenLoop, template: ServoConstants,
                         solve_for: str = "leakage") -> ServoConstants:
    """Invert eq 6.16 (with the damping of `open_loop_from_servo`): the constants that
    give the loop `ol`, the others held at the template's.

    Eq 6.16 fixes three combinations: k = k_o A_e, β/V = ω_o² m/(4A A_e) and
    D = k_ct + k k_p = (2ξ_o A A_e/ω_o - cV/4β)/m, with A_e = A + k k_v + c D/A (solved
    by fixed-point iteration when c > 0, c·D/A ≪ A; in closed form without damping).

    Parameters
    ----------
    ol : OpenLoop
        The loop (f_o, ξ_o, k_o) to realise.
    template : ServoConstants
        Supplies A, m, k_v, c and the constants held.
    solve_for : {"leakage", "feedback"}
        "leakage": k_t, β and k_ct (V and k_p held; a fitted loop back to constants);
        "feedback": k_t, V and k_p (β and k_ct held; an actuator designed for a loop).

    Raises
    ------
    VtableError
        When no positive k_t exists (k_o k_v ≥ 1) or the damping asks for a negative
        k_ct (resp. k_p).
    """
    if solve_for not in UNKNOWNS:
        raise VtableError(f"solve_for must be one of {', '.join(UNKNOWNS)}, got {solve_for!r}")
    A, kv, c, m = template.area, template.k_v, template.damping or 0.0, template.mass
    if ol.k_o * kv >= 1:
        raise VtableError(f"k_o·k_v = {ol.k_o * kv:g} >= 1: no positive k_t gives k_o = "
                          f"{ol.k_o:g} with this velocity feedback")
    w = ol.omega_o
    held_kp = solve_for == "leakage"
    kp, k_ct = template.k_p, template.k_ct
    beta, V = template.beta, template.volume
    D = k_ct + (kp * ol.k_o * A if held_kp else 0.0)  # start: c = 0 guess of k_ct + k k_p
    for _ in range(50 if c else 1):
        k = ol.k_o * (A + c * D / A) / (1 - ol.k_o * kv)
        A_e = A + k * kv + c * D / A
        beta_over_v = w**2 * m / (4 * A * A_e)
        if held_kp:
            beta = beta_over_v * V
        else:
            V = beta / beta_over_v
        new = (2 * ol.xi_o * A * A_e / w - c / (4 * beta_over_v)) / m
        done = abs(new - D) <= 1e-14 * max(abs(new), 1e-30)
        D = new
        if done:
            break
    if held_kp:
        k_ct = D - k * kp
        if k_ct < 0:
            raise VtableError(f"ξ_o = {ol.xi_o:g} is below what the pressure feedback and "
                              "the damping alone give: the flow-pressure coefficient k_ct "
                              "would be negative")
        return dataclasses.replace(template, k_t=k, beta=beta, k_ct=k_ct)
    kp = (D - k_ct) / k
    if kp < 0:
        raise VtableError(f"ξ_o = {ol.xi_o:g} is below what the valve leakage k_ct and the "
                          "damping alone give: the pressure feedback k_p would be negative")
    return dataclasses.replace(template, k_t=k, volume=V, k_p=kp)


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
        row, b = loop_row(open_loop)
        A = np.vstack([[0, 1, 0], [0, 0, 1], row])
        B = np.array([[0], [0], [b]])
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
