"""The reduced model's integrator (numba): generalized coordinates q with mass, stiffness
and damping matrices, one equivalent horizontal actuator stepped by the hydraulic element
(`vtable.hydraulics.element.servo_rates`), auxiliary linear states w (other control loops:
ẇ = Aw w + Wq q + Wv q̇, generalized force Fw w), quadratic dampers c₂|q̇|q̇, and force
elements with states z (`elem(q, q̇, z, p, f, ż)` adds generalized forces to f).

`simulate_reduced` integrates a model without force elements (the catalog's); it is
cached on disk, so every process loads it compiled. `simulate_reduced_elements` wraps the
same rates with a user's element function (compiled once per process: a cache entry typed
on a function from a user's file could not be loaded by another process), and
`simulate_reduced_python` runs that code as Python for a law numba cannot compile.

A linear model (no force element, no quadratic damper, a linear hydraulic loop) is the
state-space system ẏ = A y + B x_c whose A and B are the same rates evaluated on unit
states (`linear_system`); `simulate_linear` steps it exactly for a command linear between
samples (first-order hold: the exponential of the augmented matrix over one step), the
same input the RK4 integrator assumes, at a fraction of its cost.
"""

from __future__ import annotations

import types

import numpy as np
import scipy.linalg
from numba import njit

from vtable.hydraulics.element import servo_rates


def work_size(nq: int) -> int:
    """Length of `_rates`'s scratch array."""
    return 7 + nq


@njit(cache=True)
def _rates(y, xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw, fe, dy,
           ws):
    """Rates of the main state y = [q, q̇, servo (3), w] with extra generalized forces fe;
    returns the actuator force. `ws`: scratch of `work_size(nq)` (no allocation per call:
    this runs four times per step)."""
    q = y[:nq]
    qd = y[nq:2 * nq]
    z = y[2 * nq:2 * nq + 3].reshape(1, 3)
    na = Aw.shape[0]
    w = y[2 * nq + 3:2 * nq + 3 + na]
    xa, va, qcv, force = ws[0:1], ws[1:2], ws[2:3], ws[3:4]
    dz = ws[4:7].reshape(1, 3)
    rhs = ws[7:7 + nq]
    xa[0] = 0.0
    va[0] = 0.0
    for i in range(nq):
        xa[0] += ax[i] * q[i]
        va[0] += ax[i] * qd[i]
    qcv[0] = xc
    servo_rates(z, xa, va, qcv, T, Tp, g, kp, kv, sp, dz, force)
    for i in range(nq):
        s = bF[i] * force[0] + fe[i]
        for j in range(nq):
            s -= K[i, j] * q[j] + C[i, j] * qd[j]
        for j in range(na):
            s += Fw[i, j] * w[j]
        s -= c2[i] * abs(qd[i]) * qd[i]
        rhs[i] = s
    for i in range(nq):
        dy[i] = qd[i]
        acc = 0.0
        for j in range(nq):
            acc += Minv[i, j] * rhs[j]
        dy[nq + i] = acc
    for i in range(3):
        dy[2 * nq + i] = dz[0, i]
    for a in range(na):
        s = 0.0
        for b in range(na):
            s += Aw[a, b] * w[b]
        for j in range(nq):
            s += Wq[a, j] * q[j] + Wv[a, j] * qd[j]
        dy[2 * nq + 3 + a] = s
    return force[0]


@njit(cache=True, nogil=True)
def simulate_reduced(xc, dt, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw):
    """RK4 at step dt (the command linear between samples); returns q, q̇, q̈ (n_t x nq)
    and the actuator force (n_t). A state that blows up ends the run with NaN."""
    n = xc.shape[0]
    ny = 2 * nq + 3 + Aw.shape[0]
    fe = np.zeros(nq)
    ws = np.zeros(7 + nq)
    y = np.zeros(ny)
    yt = np.empty(ny)
    Q, Qd, Qdd, F = np.empty((n, nq)), np.empty((n, nq)), np.empty((n, nq)), np.empty(n)
    k1, k2, k3, k4 = np.empty(ny), np.empty(ny), np.empty(ny), np.empty(ny)
    for k in range(n):
        F[k] = _rates(y, xc[k], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv,
                      Fw, fe, k1, ws)
        Q[k], Qd[k], Qdd[k] = y[:nq], y[nq:2 * nq], k1[nq:2 * nq]
        if k == n - 1:
            break
        xm = 0.5 * (xc[k] + xc[k + 1])
        for i in range(ny):
            yt[i] = y[i] + 0.5 * dt * k1[i]
        _rates(yt, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw, fe, k2,
               ws)
        for i in range(ny):
            yt[i] = y[i] + 0.5 * dt * k2[i]
        _rates(yt, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw, fe, k3,
               ws)
        for i in range(ny):
            yt[i] = y[i] + dt * k3[i]
        _rates(yt, xc[k + 1], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
               fe, k4, ws)
        for i in range(ny):
            y[i] += dt / 6.0 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i])
        if not np.isfinite(y[0]) or abs(y[0]) > 10.0:
            Q[k + 1:], Qd[k + 1:], Qdd[k + 1:], F[k + 1:] = np.nan, np.nan, np.nan, np.nan
            break
    return Q, Qd, Qdd, F


def _element_rates(y, xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
                   elem, ne, pe, dy):
    """Rates of y = [main state, element states]: the elements' forces, then `_rates`."""
    m = y.shape[0] - ne
    fe = np.zeros(nq)
    dze = np.zeros(ne)
    elem(y[:nq], y[nq:2 * nq], y[m:], pe, fe, dze)
    force = _rates(y[:m], xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
                   fe, dy[:m], np.zeros(7 + nq))
    for k in range(ne):
        dy[m + k] = dze[k]
    return force


def _element_integrate(xc, dt, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv,
                       Fw, elem, ne, pe):
    """`simulate_reduced` with force elements (see `_element_rates`)."""
    n = xc.shape[0]
    ny = 2 * nq + 3 + Aw.shape[0] + ne
    y = np.zeros(ny)
    Q, Qd, Qdd, F = np.empty((n, nq)), np.empty((n, nq)), np.empty((n, nq)), np.empty(n)
    k1, k2, k3, k4 = np.empty(ny), np.empty(ny), np.empty(ny), np.empty(ny)
    for k in range(n):
        F[k] = _element_rates(y, xc[k], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw,
                              Wq, Wv, Fw, elem, ne, pe, k1)
        Q[k], Qd[k], Qdd[k] = y[:nq], y[nq:2 * nq], k1[nq:2 * nq]
        if k == n - 1:
            break
        xm = 0.5 * (xc[k] + xc[k + 1])
        _element_rates(y + 0.5 * dt * k1, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv,
                       Aw, Wq, Wv, Fw, elem, ne, pe, k2)
        _element_rates(y + 0.5 * dt * k2, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv,
                       Aw, Wq, Wv, Fw, elem, ne, pe, k3)
        _element_rates(y + dt * k3, xc[k + 1], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp,
                       kv, Aw, Wq, Wv, Fw, elem, ne, pe, k4)
        y += dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        if not np.isfinite(y[0]) or abs(y[0]) > 10.0:
            Q[k + 1:], Qd[k + 1:], Qdd[k + 1:], F[k + 1:] = np.nan, np.nan, np.nan, np.nan
            break
    return Q, Qd, Qdd, F


def simulate_reduced_python(*args):
    """`_element_integrate` as plain Python (the compiled `_rates` does the rest)."""
    return _element_integrate(*args)


_COMPILED: list = []


def simulate_reduced_elements(*args):
    """`_element_integrate` compiled (once per process, not cached on disk)."""
    if not _COMPILED:
        glb = dict(_element_integrate.__globals__)
        glb["_element_rates"] = njit(_element_rates)
        _COMPILED.append(njit(nogil=True)(types.FunctionType(_element_integrate.__code__, glb)))
    return _COMPILED[0](*args)


def linear_system(nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw):
    """(A, B, f_y, f_u) of a linear model: ẏ = A y + B x_c and the actuator force
    f_y·y + f_u x_c, from `_rates` on unit states (exact: the rates are linear)."""
    ny = 2 * nq + 3 + Aw.shape[0]
    fe = np.zeros(nq)
    A, fy = np.empty((ny, ny)), np.empty(ny)
    dy, y = np.empty(ny), np.zeros(ny)
    ws = np.zeros(work_size(nq))
    for j in range(ny):
        y[:] = 0.0
        y[j] = 1.0
        fy[j] = _rates(y, 0.0, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
                       fe, dy, ws)
        A[:, j] = dy
    y[:] = 0.0
    fu = _rates(y, 1.0, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw, fe, dy,
                ws)
    return A, dy.copy(), fy, fu


def hold_matrices(A: np.ndarray, B: np.ndarray, h: float):
    """(Φ, Γ₀, Γ₁): y_{k+1} = Φ y_k + Γ₀ u_k + Γ₁ (u_{k+1} - u_k) for u linear over the
    step h (the exponential of [[A, B, 0], [0, 0, 1/h], [0, 0, 0]] h)."""
    n = A.shape[0]
    M = np.zeros((n + 2, n + 2))
    M[:n, :n], M[:n, n], M[n, n + 1] = A * h, B * h, 1.0
    # pressures (Pa) beside displacements (m): balance first, or the exponential's norm
    # (and its squarings) follows the units
    Mb, (scale, _) = scipy.linalg.matrix_balance(M, permute=False, separate=True)
    E = scipy.linalg.expm(Mb) * scale[:, None] / scale[None, :]
    return (np.ascontiguousarray(E[:n, :n]), np.ascontiguousarray(E[:n, n]),
            np.ascontiguousarray(E[:n, n + 1]))


@njit(cache=True, nogil=True)
def simulate_linear(xc, nq, A, B, fy, fu, Phi, G0, G1):
    """The linear model stepped exactly (see the module docstring); the same outputs as
    `simulate_reduced`, NaN from where a state blows up."""
    n = xc.shape[0]
    ny = A.shape[0]
    y = np.zeros(ny)
    yn = np.empty(ny)
    Q, Qd, Qdd, F = np.empty((n, nq)), np.empty((n, nq)), np.empty((n, nq)), np.empty(n)
    for k in range(n):
        u = xc[k]
        f = fu * u
        for j in range(ny):
            f += fy[j] * y[j]
        F[k] = f
        for i in range(nq):
            Q[k, i] = y[i]
            Qd[k, i] = y[nq + i]
            a = B[nq + i] * u
            for j in range(ny):
                a += A[nq + i, j] * y[j]
            Qdd[k, i] = a
        if k == n - 1:
            break
        du = xc[k + 1] - u
        for i in range(ny):
            s = G0[i] * u + G1[i] * du
            for j in range(ny):
                s += Phi[i, j] * y[j]
            yn[i] = s
        y[:] = yn
        if not np.isfinite(y[0]) or abs(y[0]) > 10.0:
            Q[k + 1:], Qd[k + 1:], Qdd[k + 1:], F[k + 1:] = np.nan, np.nan, np.nan, np.nan
            break
    return Q, Qd, Qdd, F
