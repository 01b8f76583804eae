"""x_t/x_c of the bare platen under any declared controller: eq 6.15 generalised.

Eq 6.15 is the closed loop of the report's analog controller (P on the displacement
error, ΔP and velocity feedback, eqs 6.1-6.4) on a rigid platen. A digital controller
adds terms (`vtable.controllers.kinds`: integral, derivative, feedforward, notches,
acceleration feedback, a reference generator) that enter the hydraulic element as its
control stage; the loop is then the element's linear blocks (`ServoLaw.linear_blocks`,
the same law the virtual table and the reduced model step) closed around the platen:

    ż = A z + B_x x + B_v ẋ + B_c x_c,   F = C z,   M ẍ + c ẋ = F
    x/x_c = G B_c / (M s² + c s - G (B_x + s B_v)),   G(s) = C (sI - A)⁻¹

with the loop's constants from (f_o, ξ_o, k_o) by eq 6.16 inverted and a valve lag τ.
Without a control stage it is eq 6.15 (τ = 0) or eq 6.15 with a valve lag.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from vtable.analytic.servo import servo_from_open_loop
from vtable.hydraulics.law import group_law
from vtable.hydraulics.table_stages import SPOOL_LAG
from vtable.params.loops import OpenLoop
from vtable.params.virtual import VirtualTable

TWO_PI = 2 * np.pi


def declared_loop(vt: VirtualTable):
    """``h(f_hz, f_o, xi_o, k_o, tau)``: x_t/x_c of `vt`'s bare platen under its declared
    controller (`vt.control`), the loop at (f_o, ξ_o, k_o) (eq 6.16 on the platen mass per
    actuator), the valve lag τ (s; 0: none).

    Parameters
    ----------
    vt
        The run's table (`vtable.runs.lab.run_table`).

    Returns
    -------
    Callable
        The frequency response at `f_hz` (complex array).
    """
    n = len(vt.group("horizontal"))
    mass = vt.table.geometry.mass
    template = dataclasses.replace(vt.horizontal_servo, mass=mass / n)
    damping = (vt.horizontal_servo.damping or 0.0) * n

    def h(f_hz, f_o: float, xi_o: float, k_o: float, tau: float) -> np.ndarray:
        servo = dataclasses.replace(servo_from_open_loop(OpenLoop(f_o, xi_o, k_o), template),
                                    rc=0.0)
        stages = ([(SPOOL_LAG, {"tau": tau})] if tau > 0 else []) + \
            ([vt.control.use] if vt.control is not None else [])
        b = group_law(vt, "horizontal", servo, stages=stages).lumped("x").linear_blocks()
        s = 1j * TWO_PI * np.asarray(f_hz, dtype=float)
        eye = np.eye(b.A.shape[0])
        out = np.empty(len(s), dtype=complex)
        for k, sk in enumerate(s):
            G = np.linalg.solve((sk * eye - b.A).T, b.C[0])  # C (sI - A)⁻¹
            out[k] = (G @ b.Bc[:, 0]) / (mass * sk**2 + damping * sk
                                          - G @ (b.Bx[:, 0] + sk * b.Bv[:, 0]))
        return out

    return h
