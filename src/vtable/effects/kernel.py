"""Compiled kernels (numba) shared by the virtual table and the reduced model, so that
the physics of the servo effects is written once.

`servo_rates` is the horizontal actuator group: per actuator a load pressure P_L, the
RC-filtered pressure P_f (eq B.4) and the valve flow q_v (spool lag), under the DOF
control law of eqs 6.1-6.4 (drive = T G [(q_c - q) - k_p P̄_f - k_v q̇]) with the appendix C
nonlinearities switched by their parameters:

  q = k_t·drive, lagged by τ (valve_dynamics), clipped at ±q_max (flow_saturation),
      times √(1 - sign(q) P_L/P_s) (valve_flow_nonlinearity, eq C.14)
  (V/4β_e) Ṗ_L = q - k_ct P_L - A v, 1/β_e = 1/β + r/(1.4 P) (oil_column_air, eq C.10)
  F = A P_L - F_r tanh(v/v_ε) (actuator_friction, eq C.12)

`simulate_reduced` integrates the planar reduced model (table, optional pitch and
foundation DOFs, storeys) with one equivalent actuator by RK4.
"""

from __future__ import annotations

import numpy as np
from numba import njit

# servo parameter vector indices
A, V, BETA, KT, KCT, KP, KV, RC, PS, FR, QMAX, TAU, AIR, PMEAN, VEPS = range(15)
N_SERVO = 15
ATM = 101325.0


@njit(cache=True)
def servo_rates(z, x, v, qc, T, Tp, g, kp, kv, sp, dz, force):
    """Rates dz (n x 3: P_L, P_f, q_v) and forces (n) of a group of n actuators."""
    n, d = T.shape
    P = z[:, 0]
    e = np.empty(d)
    for j in range(d):
        acc_x = 0.0
        acc_v = 0.0
        acc_p = 0.0
        for i in range(n):
            acc_x += Tp[j, i] * x[i]
            acc_v += Tp[j, i] * v[i]
            acc_p += Tp[j, i] * (z[i, 1] if sp[RC] > 0 else P[i])
        e[j] = g[j] * ((qc[j] - acc_x) - kp[j] * acc_p - kv[j] * acc_v)
    for i in range(n):
        drive = 0.0
        for j in range(d):
            drive += T[i, j] * e[j]
        qcmd = sp[KT] * drive
        if sp[TAU] > 0:
            dz[i, 2] = (qcmd - z[i, 2]) / sp[TAU]
            q = z[i, 2]
        else:
            dz[i, 2] = 0.0
            q = qcmd
        if sp[QMAX] > 0:
            q = min(max(q, -sp[QMAX]), sp[QMAX])
        if sp[PS] > 0:
            s = 1.0 - (P[i] if q >= 0 else -P[i]) / sp[PS]
            q *= np.sqrt(s) if s > 0 else 0.0
        beta = sp[BETA]
        if sp[AIR] > 0:
            p1 = max(0.5 * sp[PMEAN] + 0.5 * P[i], 0.0) + ATM
            p2 = max(0.5 * sp[PMEAN] - 0.5 * P[i], 0.0) + ATM
            beta = 1.0 / (1.0 / sp[BETA] + sp[AIR] / 1.4 * 0.5 * (1.0 / p1 + 1.0 / p2))
        dP = 4.0 * beta / sp[V] * (q - sp[KCT] * P[i] - sp[A] * v[i])
        dz[i, 0] = dP
        dz[i, 1] = (-z[i, 1] / sp[RC] + dP) if sp[RC] > 0 else 0.0
        force[i] = sp[A] * P[i] - sp[FR] * np.tanh(v[i] / sp[VEPS])


@njit(cache=True)
def servo_step(z, x0, x1, v, v_prev, c0, c1, dt, T, Tp, g, kp, kv, sp, force):
    """Advance the group over one simulator step (x linear from x0 to x1, the step-average
    velocity v held, commands linear from c0 to c1; two RK4 substeps) and return the
    forces at its end, friction evaluated at v̂ = 1.5 v - 0.5 v_prev."""
    n = z.shape[0]
    h = dt / 2
    k1 = np.empty_like(z)
    k2 = np.empty_like(z)
    k3 = np.empty_like(z)
    k4 = np.empty_like(z)
    f = np.empty(n)
    for sub in range(2):
        a0, am, a1 = sub * 0.5, sub * 0.5 + 0.25, sub * 0.5 + 0.5
        servo_rates(z, x0 + (x1 - x0) * a0, v, c0 + (c1 - c0) * a0, T, Tp, g, kp, kv, sp, k1, f)
        servo_rates(z + 0.5 * h * k1, x0 + (x1 - x0) * am, v, c0 + (c1 - c0) * am, T, Tp, g, kp,
                    kv, sp, k2, f)
        servo_rates(z + 0.5 * h * k2, x0 + (x1 - x0) * am, v, c0 + (c1 - c0) * am, T, Tp, g, kp,
                    kv, sp, k3, f)
        servo_rates(z + h * k3, x0 + (x1 - x0) * a1, v, c0 + (c1 - c0) * a1, T, Tp, g, kp, kv,
                    sp, k4, f)
        z += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    dz = np.empty_like(z)
    servo_rates(z, x1, 1.5 * v - 0.5 * v_prev, c1, T, Tp, g, kp, kv, sp, dz, force)


@njit(cache=True)
def _reduced_rates(y, xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
                   dy):
    q = y[:nq]
    qd = y[nq:2 * nq]
    z = y[2 * nq:2 * nq + 3].reshape(1, 3)
    w = y[2 * nq + 3:]
    na = w.shape[0]
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
    rhs = np.empty(nq)
    for i in range(nq):
        s = bF[i] * force[0]
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
    return force[0]


@njit(cache=True, nogil=True)
def simulate_reduced(xc, dt, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw):
    """RK4 at step dt; returns q, q̇, q̈ (n_t x nq) and the actuator force (n_t).

    Auxiliary linear states w (ẇ = Aw w + Wq q + Wv q̇, generalized force Fw w) carry other
    linear loops (the pitch DOF loop of the vertical actuators)."""
    n = xc.shape[0]
    ny = 2 * nq + 3 + Aw.shape[0]
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
        F[k] = _reduced_rates(y, xc[k], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq,
                              Wv, Fw, k1)
        Q[k] = y[:nq]
        Qd[k] = y[nq:2 * nq]
        Qdd[k] = k1[nq:2 * nq]
        if k == n - 1:
            break
        xm = 0.5 * (xc[k] + xc[k + 1])
        _reduced_rates(y + 0.5 * dt * k1, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv,
                       Aw, Wq, Wv, Fw, k2)
        _reduced_rates(y + 0.5 * dt * k2, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv,
                       Aw, Wq, Wv, Fw, k3)
        _reduced_rates(y + dt * k3, xc[k + 1], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv,
                       Aw, Wq, Wv, Fw, k4)
        y += dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        if not np.isfinite(y[0]) or abs(y[0]) > 10.0:
            Q[k + 1:] = np.nan
            Qd[k + 1:] = np.nan
            Qdd[k + 1:] = np.nan
            F[k + 1:] = np.nan
            break
    return Q, Qd, Qdd, F
