"""The hydraulic element: a group of servo-hydraulic actuators under DOF control, with the
appendix C nonlinearities as named options, compiled with numba.

Per actuator: load pressure P_L, the RC-filtered pressure P_f (eq B.4) and the valve flow
q_v (spool lag). The DOF law (`law.ServoLaw`) gives the drive:

  drive = T G [(q_c - q) - k_p P̄_f - k_v q̇],  q = T⁺x,  P̄ = T⁺P        (eqs 6.1-6.4)
  q = k_t·drive, lagged by τ (spool_lag), clipped at ±max_flow, times
      √(1 - sign(q) P_L/P_s) with a supply pressure P_s (orifice flow, eq C.14)
  (V/4β_e) Ṗ_L = q - k_ct P_L - A v,  β_e = (β₁ + β₂)/2 with 1/β_i = 1/β + r/(1.4 P_i)
      for the chambers at P_s/2 ± P_L/2 (air_ratio, eqs C.6-C.11)
  F = A P_L - F_r tanh(v/v_ε)                                             (eq C.12)

`HydraulicParams` names every constant; `vector()` lays them out for the kernel, and the
slot numbers below are used nowhere else.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from vtable._numba import njit

# kernel slots (this module only)
_A, _V, _BETA, _KT, _KCT, _RC, _PS, _FR, _QMAX, _TAU, _AIR, _PMEAN, _VEPS = range(13)
_N = 13
ATM = 101325.0  # Pa: the chamber pressure floor of the air law


@dataclass(frozen=True)
class HydraulicParams:
    """One actuator's loop constants (SI; eqs 6.1-6.5, B.4-B.6, Table B.5) and the
    appendix C options, 0 meaning "not present".

    `k_p`, `k_v` are the group's reference feedback gains (the DOF law scales them by the
    knob factors); `mean_pressure` is the chamber pressure at rest (P_s/2 per chamber,
    given as the supply pressure) used by the air law.
    """

    area: float
    volume: float
    beta: float
    k_t: float
    k_ct: float
    k_p: float
    k_v: float = 0.0
    rc: float = 0.0
    supply_pressure: float = 0.0
    friction: float = 0.0
    max_flow: float = 0.0
    spool_lag: float = 0.0
    air_ratio: float = 0.0
    mean_pressure: float = 0.0
    friction_velocity: float = 1e-3

    @property
    def nonlinear(self) -> bool:
        """Whether any appendix C option is on (otherwise the loop is linear)."""
        return any((self.supply_pressure, self.friction, self.max_flow, self.spool_lag,
                    self.air_ratio))

    @property
    def linear(self) -> bool:
        """Whether the loop is linear (a spool lag is; the orifice, friction, the flow cap
        and the air law are not)."""
        return not any((self.supply_pressure, self.friction, self.max_flow, self.air_ratio))

    def lumped(self, n: int) -> HydraulicParams:
        """`n` identical actuators acting together as one: areas, volumes, flows, leakage
        and friction add; pressures and gains stay."""
        return dataclasses.replace(self, area=n * self.area, volume=n * self.volume,
                                   k_t=n * self.k_t, k_ct=n * self.k_ct,
                                   friction=n * self.friction, max_flow=n * self.max_flow)

    def replace(self, **changes: float) -> HydraulicParams:
        return dataclasses.replace(self, **changes)

    def vector(self) -> np.ndarray:
        """The kernel's parameter vector."""
        v = np.zeros(_N)
        v[_A], v[_V], v[_BETA] = self.area, self.volume, self.beta
        v[_KT], v[_KCT], v[_RC] = self.k_t, self.k_ct, self.rc
        v[_PS], v[_FR], v[_QMAX] = self.supply_pressure, self.friction, self.max_flow
        v[_TAU], v[_AIR], v[_VEPS] = self.spool_lag, self.air_ratio, self.friction_velocity
        v[_PMEAN] = self.supply_pressure or self.mean_pressure
        return v


@njit(cache=True)
def dof_error(qc, q, p, qd, g, kp, kv):
    """One DOF's drive (eqs 6.1-6.4): g [(q_c - q) - k_p P̄ - k_v q̇]."""
    return g * ((qc - q) - kp * p - kv * qd)


@njit(cache=True)
def fed_back_pressure(P, Pf, sp):
    """The pressure the ΔP feedback reads: the RC-filtered P_f when there is an RC filter
    (eq B.4), else P_L."""
    return Pf if sp[_RC] > 0 else P


@njit(cache=True)
def actuator_rates(P, Pf, qv, drive, v, sp):
    """One actuator under its drive (see the module docstring): the rates of its load
    pressure P_L, its RC-filtered pressure P_f and its valve flow q_v, and its force."""
    qcmd = sp[_KT] * drive
    if sp[_TAU] > 0:
        dqv = (qcmd - qv) / sp[_TAU]
        q = qv
    else:
        dqv = 0.0
        q = qcmd
    if sp[_QMAX] > 0:
        q = min(max(q, -sp[_QMAX]), sp[_QMAX])
    if sp[_PS] > 0:
        s = 1.0 - (P if q >= 0 else -P) / sp[_PS]
        q *= np.sqrt(s) if s > 0 else 0.0
    beta = sp[_BETA]
    if sp[_AIR] > 0:
        p1 = max(0.5 * sp[_PMEAN] + 0.5 * P, 0.0) + ATM
        p2 = max(0.5 * sp[_PMEAN] - 0.5 * P, 0.0) + ATM
        # each chamber (V/2) its own modulus, eqs C.6-C.11: Ṗ_L = (2/V)(β₁ + β₂)·flow
        beta = 0.5 / (1.0 / sp[_BETA] + sp[_AIR] / (1.4 * p1)) + \
            0.5 / (1.0 / sp[_BETA] + sp[_AIR] / (1.4 * p2))
    dP = 4.0 * beta / sp[_V] * (q - sp[_KCT] * P - sp[_A] * v)
    dPf = (-Pf / sp[_RC] + dP) if sp[_RC] > 0 else 0.0
    force = sp[_A] * P - sp[_FR] * np.tanh(v / sp[_VEPS])
    return dP, dPf, dqv, force


@njit(cache=True)
def servo_rates(z, x, v, qc, T, Tp, g, kp, kv, sp, dz, force):
    """Rates dz (n x 3: P_L, P_f, q_v) and forces (n) of a group of n actuators: each
    actuator's drive T G e from the DOF errors (`dof_error`), then `actuator_rates`."""
    n, d = T.shape
    for i in range(n):
        drive = 0.0
        for j in range(d):
            acc_x = 0.0
            acc_v = 0.0
            acc_p = 0.0
            for a in range(n):
                acc_x += Tp[j, a] * x[a]
                acc_v += Tp[j, a] * v[a]
                acc_p += Tp[j, a] * fed_back_pressure(z[a, 0], z[a, 1], sp)
            drive += T[i, j] * dof_error(qc[j], acc_x, acc_p, acc_v, g[j], kp[j], kv[j])
        dz[i, 0], dz[i, 1], dz[i, 2], force[i] = actuator_rates(z[i, 0], z[i, 1], z[i, 2],
                                                                drive, v[i], sp)


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
