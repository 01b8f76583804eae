"""The hydraulic element: a group of servo-hydraulic actuators under DOF control, compiled
with numba — the linear servo law, and the interface its stages plug into.

Per actuator the load pressure P_L, and the states of its stages (`stage`). The DOF law
(`law.ServoLaw`) gives the drive:

  drive = T G [(q_c - q) - k_p P̄_f - k_v q̇],  q = T⁺x,  P̄ = T⁺P        (eqs 6.1-6.4)
  q_v = k_t·drive                                     (the servovalve, eq 6.2)
  (V/4β) Ṗ_L = q_v - k_ct P_L - A v,   F = A P_L         (the oil column, eqs 6.2-6.3)

and every effect's physics enters as a stage between those lines (`compose`: valve, flow,
pressure, feedback and force stages). With no stage this module is the linear element
(`servo_rates`, `servo_step` here); a stage set is compiled into its own module
(`compose.composition`) from the same text.

The actuator's linear constants are the table's `ServoConstants` (one actuator type);
`constants_vector` lays them out for the kernel, and the slot numbers below are used
nowhere else.
"""

from __future__ import annotations

import numpy as np

from vtable._numba import njit
from vtable.params.table import ServoConstants

# kernel slots (this module only); a composition's stage parameters follow them
_A, _V, _BETA, _KT, _KCT = range(5)
N_LINEAR = 5
PISTON_AREA = _A  #: the piston area's slot, for A P_L outside the kernels (eq 6.3)
NS = 1  # states per actuator without stages: P_L


def constants_vector(c: ServoConstants) -> np.ndarray:
    """The kernel's parameter vector of one actuator's linear constants (`ServoConstants`,
    eqs 6.2-6.3: A, V, β, k_t, k_ct); the stages' named parameters follow it
    (`compose.Composition.vector`)."""
    v = np.zeros(N_LINEAR)
    v[_A], v[_V], v[_BETA] = c.area, c.volume, c.beta
    v[_KT], v[_KCT] = c.k_t, c.k_ct
    return v


@njit(cache=True)
def dof_error(qc, q, p, qd, g, kp, kv):
    """One DOF's drive (eqs 6.1-6.4): g [(q_c - q) - k_p P̄ - k_v q̇]."""
    return g * ((qc - q) - kp * p - kv * qd)


@njit(cache=True)
def dof_drive(qc, q, p, qd, g, kp, kv, z, o, sp, dz, ctl):
    """One DOF's drive through the controller (`dof_error`: no control stage; a control
    stage's states start at z[o + 1], the actuator's whose drive it makes, and it acts on
    the DOF called with `ctl` true: the law's first, x)."""
    return dof_error(qc, q, p, qd, g, kp, kv)


@njit(cache=True)
def commanded_flow(drive, sp):
    """The servovalve's flow for a drive (eq 6.2): k_t·drive."""
    return sp[_KT] * drive


@njit(cache=True)
def bulk_modulus(sp):
    """The oil's bulk modulus β (Table B.5)."""
    return sp[_BETA]


@njit(cache=True)
def oil_column(q, P, v, beta, sp):
    """Ṗ_L of the oil column (eq 6.2): (4β/V)(q - k_ct P_L - A v)."""
    return 4.0 * beta / sp[_V] * (q - sp[_KCT] * P - sp[_A] * v)


@njit(cache=True)
def piston_force(P, sp):
    """The force on the platen (eq 6.3): A P_L."""
    return sp[_A] * P


@njit(cache=True)
def fed_back(z, o, sp):
    """The pressure the ΔP feedback reads of the actuator whose states start at z[o]."""
    return z[o]


@njit(cache=True)
def actuator_rates(z, o, drive, v, sp, dz):
    """One actuator (states from z[o]) under its drive: writes the rates from dz[o] and
    returns its force."""
    P = z[o]
    dz[o] = oil_column(commanded_flow(drive, sp), P, v, bulk_modulus(sp), sp)
    return piston_force(P, sp)


@njit(cache=True)
def servo_rates(z, x, v, qc, T, Tp, g, kp, kv, sp, dz, force):
    """Rates dz (n·NS: each actuator's states in turn) and forces (n) of a group of n
    actuators: each actuator's drive T G e from the DOF errors (`dof_drive`), then
    `actuator_rates`. A control stage runs one copy per actuator on the law's first DOF
    (x; `law.ServoLaw` refuses it on a law whose first DOF is another)."""
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
                acc_p += Tp[j, a] * fed_back(z, a * NS, sp)
            drive += T[i, j] * dof_drive(qc[j], acc_x, acc_p, acc_v, g[j], kp[j], kv[j], z,
                                         i * NS, sp, dz, j == 0)
        force[i] = actuator_rates(z, i * NS, drive, v[i], sp, dz)


@njit(cache=True)
def servo_step(z, x0, x1, v, v_prev, c0, c1, dt, T, Tp, g, kp, kv, sp, force):
    """Advance the group over one simulator step (x linear from x0 to x1, the step-average
    velocity v held, commands linear from c0 to c1; two RK4 substeps) and return the
    forces at its end, a force stage evaluated at v̂ = 1.5 v - 0.5 v_prev."""
    n = T.shape[0]
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
