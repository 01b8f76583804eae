"""Linearisation of the right-hand side (finite differences) and its modes (eqs 9.1-9.4)."""

from __future__ import annotations

import numpy as np

from . import model as m
from .build import Built, build
from .specimens import Specimen
from .tables import Table

SCALE = {m.S_X: 1e-3, m.S_V: 1e-2, m.S_TH: 1e-5, m.S_OM: 1e-4, m.S_PL: 1e5, m.S_PF: 1e5,
         m.S_Q: 1e-4, m.S_XP: 1e-3, m.S_VP: 1e-2, m.S_XF: 1e-4, m.S_VF: 1e-3, m.S_MR: 1e4,
         m.S_INT: 1e-3, m.S_Z: 1e-4, m.S_XR: 1e-3, m.S_VR: 1e-2, m.S_DF: 1e-3, m.S_XG: 1e-3,
         m.S_VG: 1e-2}


def jacobian(b: Built, rel: float = 1e-4) -> tuple[np.ndarray, list[int]]:
    """∂ṡ/∂s at rest (x_c = 0) over the active states, by central differences. A pure valve
    delay is left out (it has no finite state); everything else is in."""
    act = b.active_states()
    fl = b.fl.copy()
    fl[m.F_DELAY] = 0
    ns = b.n_state
    s0 = np.zeros(ns)
    ds = np.zeros(ns)
    aux = np.zeros(m.N_AUX)
    J = np.zeros((len(act), len(act)))
    for col, i in enumerate(act):
        h = rel * SCALE.get(i, 1e-3 if i < m.N_BASE + b.fl[m.F_N] else 1e-2)
        sp, sm = s0.copy(), s0.copy()
        sp[i] += h
        sm[i] -= h
        m.rhs(0.0, sp, 0.0, 0.0, 0.0, 0.0, b.p, fl, b.Ms, b.Ks, b.Cs, b.hs, b.c2s, b.hy, ds,
              aux)
        fp = ds[act].copy()
        m.rhs(0.0, sm, 0.0, 0.0, 0.0, 0.0, b.p, fl, b.Ms, b.Ks, b.Cs, b.hs, b.c2s, b.hy, ds,
              aux)
        J[:, col] = (fp - ds[act]) / (2 * h)
    return J, act


def modes(table: Table, spec: Specimen) -> tuple[list[tuple[float, float]], list[float]]:
    """Oscillatory modes (f Hz, ξ) sorted by frequency, and the real roots (1/s), of the
    linearised system (eqs 9.2-9.4)."""
    J, _ = jacobian(build(table, spec, 5e-4))
    lam = np.linalg.eigvals(J)
    osc = sorted({(round(float(abs(x)) / (2 * np.pi), 9), round(float(-x.real / abs(x)), 9))
                  for x in lam if x.imag > 1e-9 * max(1.0, abs(x))})
    real = sorted(float(x.real) for x in lam if abs(x.imag) <= 1e-9 * max(1.0, abs(x)))
    return list(osc), real


def input_matrix(b: Built, h: float = 1e-3) -> np.ndarray:
    """∂ṡ/∂(x_c, ẋ_c, ẍ_c) at rest over the active states (columns), by central
    differences: the command enters through x_c and, with feedforward or a derivative,
    through its rates."""
    act = b.active_states()
    fl = b.fl.copy()
    fl[m.F_DELAY] = 0
    s0 = np.zeros(b.n_state)
    ds = np.zeros(b.n_state)
    aux = np.zeros(m.N_AUX)
    B = np.zeros((len(act), 3))
    for col in range(3):
        u = np.zeros(3)
        u[col] = h
        m.rhs(0.0, s0, u[0], u[1], u[2], 0.0, b.p, fl, b.Ms, b.Ks, b.Cs, b.hs, b.c2s, b.hy, ds,
              aux)
        fp = ds[act].copy()
        m.rhs(0.0, s0, -u[0], -u[1], -u[2], 0.0, b.p, fl, b.Ms, b.Ks, b.Cs, b.hs, b.c2s, b.hy,
              ds, aux)
        B[:, col] = (fp - ds[act]) / (2 * h)
    return B


def response(table: Table, spec: Specimen, f_hz: np.ndarray, state: int = m.S_X) -> np.ndarray:
    """The linearised truth's frequency response from x_c to one state (default x_t):
    H(s) = e_k (sI - J)⁻¹ (B₀ + s B₁ + s² B₂), s = 2πj f (no pure delay)."""
    b = build(table, spec, 5e-4)
    J, act = jacobian(b)
    B = input_matrix(b)
    k = act.index(state)
    out = np.empty(len(np.atleast_1d(f_hz)), dtype=complex)
    eye = np.eye(len(act))
    for i, f in enumerate(np.atleast_1d(f_hz)):
        s = 2j * np.pi * f
        x = np.linalg.solve(s * eye - J, B[:, 0] + s * B[:, 1] + s**2 * B[:, 2])
        out[i] = x[k]
    return out
