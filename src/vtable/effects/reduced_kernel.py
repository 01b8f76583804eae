"""The reduced model's integrator (numba): generalized coordinates q with mass, stiffness
and damping matrices, one equivalent horizontal actuator stepped by the hydraulic element
(`vtable.hydraulics.element.servo_rates`), auxiliary linear states w (other control loops:
ẇ = Aw w + Wq q + Wv q̇, generalized force Fw w), quadratic dampers c₂|q̇|q̇, and force
elements with states z (`elem(q, q̇, z, p, f, ż)` adds generalized forces to f).

The same code runs compiled (`simulate_reduced`) and, for a force law numba cannot
compile, as plain Python (`simulate_reduced.py_func`).
"""

from __future__ import annotations

import types

import numpy as np
from numba import njit

from vtable.hydraulics.element import servo_rates


@njit(cache=True)
def no_element(q, qd, z, p, f, dz):
    """The element of a model without force elements."""
    return


@njit(cache=True)
def _rates(y, xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw, elem, ne,
           pe, dy):
    q = y[:nq]
    qd = y[nq:2 * nq]
    z = y[2 * nq:2 * nq + 3].reshape(1, 3)
    na = Aw.shape[0]
    w = y[2 * nq + 3:2 * nq + 3 + na]
    ze = y[2 * nq + 3 + na:]
    xa = np.zeros(1)
    va = np.zeros(1)
    for i in range(nq):
        xa[0] += ax[i] * q[i]
        va[0] += ax[i] * qd[i]
    dz = np.empty((1, 3))
    force = np.empty(1)
    qcv = np.empty(1)
    qcv[0] = xc
    servo_rates(z, xa, va, qcv, T, Tp, g, kp, kv, sp, dz, force)
    fe = np.zeros(nq)
    dze = np.zeros(ne)
    elem(q, qd, ze, pe, fe, dze)
    rhs = np.empty(nq)
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
    dy[2 * nq:2 * nq + 3] = dz.ravel()
    for a in range(na):
        s = 0.0
        for b in range(na):
            s += Aw[a, b] * w[b]
        for j in range(nq):
            s += Wq[a, j] * q[j] + Wv[a, j] * qd[j]
        dy[2 * nq + 3 + a] = s
    for k in range(ne):
        dy[2 * nq + 3 + na + k] = dze[k]
    return force[0]


@njit(cache=True, nogil=True)
def simulate_reduced(xc, dt, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
                     elem, ne, pe):
    """RK4 at step dt (the command linear between samples); returns q, q̇, q̈ (n_t x nq)
    and the actuator force (n_t). A state that blows up ends the run with NaN."""
    n = xc.shape[0]
    ny = 2 * nq + 3 + Aw.shape[0] + ne
    y = np.zeros(ny)
    Q = np.empty((n, nq))
    Qd = np.empty((n, nq))
    Qdd = np.empty((n, nq))
    F = np.empty(n)
    k1 = np.empty(ny)
    k2 = np.empty(ny)
    k3 = np.empty(ny)
    k4 = np.empty(ny)
    for k in range(n):
        F[k] = _rates(y, xc[k], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv,
                      Fw, elem, ne, pe, k1)
        Q[k] = y[:nq]
        Qd[k] = y[nq:2 * nq]
        Qdd[k] = k1[nq:2 * nq]
        if k == n - 1:
            break
        xm = 0.5 * (xc[k] + xc[k + 1])
        _rates(y + 0.5 * dt * k1, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq,
               Wv, Fw, elem, ne, pe, k2)
        _rates(y + 0.5 * dt * k2, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq,
               Wv, Fw, elem, ne, pe, k3)
        _rates(y + dt * k3, xc[k + 1], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq,
               Wv, Fw, elem, ne, pe, k4)
        y += dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        if not np.isfinite(y[0]) or abs(y[0]) > 10.0:
            Q[k + 1:] = np.nan
            Qd[k + 1:] = np.nan
            Qdd[k + 1:] = np.nan
            F[k + 1:] = np.nan
            break
    return Q, Qd, Qdd, F


def _variant(rates):
    """`simulate_reduced`'s code calling `rates` instead."""
    glb = dict(simulate_reduced.py_func.__globals__)
    glb["_rates"] = rates
    return types.FunctionType(simulate_reduced.py_func.__code__, glb)


def simulate_reduced_python(*args):
    """`simulate_reduced` run as plain Python (for force laws numba cannot compile): the
    same code, with the rates evaluated by Python too."""
    return _variant(_rates.py_func)(*args)


_UNCACHED = []


def simulate_reduced_elements(*args):
    """`simulate_reduced` for a model with a user's force elements: the same code compiled
    without numba's on-disk cache (a cache entry typed on a function of a user's file
    could not be loaded by another process)."""
    if not _UNCACHED:
        rates = njit(types.FunctionType(_rates.py_func.__code__,
                                        dict(_rates.py_func.__globals__)))
        _UNCACHED.append(njit(nogil=True)(_variant(rates)))
    return _UNCACHED[0](*args)
