"""The nonlinear servovalve and actuator of appendix C, for the horizontal actuators.

Per actuator: two chambers with pressures P1, P2 (C.6-C.9), turbulent orifice flow through
the slave spool from the supply P_s (C.1-C.4), internal leakage across the piston C_ip,
entrained air lowering the bulk modulus with pressure (C.10-C.11), Coulomb friction F_r
(C.12), a spool stroke limit x_vm (the valve's rated flow, hence the velocity limit) and
the supply pressure as the force limit. The spool follows the same DOF control law as the
linear controller (C.13 with the DOF transforms of `servo.py`), with spool gain chosen so
that at null (P1 = P2 = P_s/2) the valve's flow gain reproduces Table B.5's k_t and the
leakage its k_ct: for small motions this controller equals the linear one.

Pressures are integrated over each step with x moving linearly and the sensed (step
average) velocity held, two Heun substeps; the force at t_k is returned (as the linear
controllers do).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vtable import units
from vtable.controllers.base import DOFS
from vtable.controllers.servo import GROUPS, dof_matrix
from vtable.params.virtual import VirtualTable

ATM = units.to_si(14.7, "psi")


@dataclass(frozen=True)
class ValveParams:
    """Appendix C constants (SI). Defaults: supply 3000 psi (§2.2); the rated flow passes
    at full spool with `rated_drop` across the valve. §C.1 quotes ratings at 1000 psi;
    the default rates the full spool at the supply pressure instead, so that the
    unloaded actuator's top speed is the rated flow over the piston area, the table's
    25 in/s (§2.2, Table 2.2). No air, no friction; leakage = Table B.5 k_ct."""

    supply_pressure: float
    rated_flow: float  # m³/s at full spool and `rated_drop`
    rated_drop: float | None = None  # Pa; None = the supply pressure
    air_ratio: float = 0.0  # r of eq C.10
    friction: float = 0.0  # F_r of eq C.12, N
    friction_velocity: float = 1e-3  # m/s, smoothing of sign(ẋ)


class NonlinearValveServo:
    """Appendix C servovalves on H1-H3 with the horizontal and twist DOF controllers."""

    def __init__(self, vt: VirtualTable, valve: ValveParams | None = None,
                 rc_filter: bool = True) -> None:
        self.vt = vt
        servo = vt.horizontal_servo
        h1 = vt.actuator("H1")
        self.valve = valve or ValveParams(supply_pressure=vt.table.geometry.supply_pressure,
                                          rated_flow=h1.flow)
        self.servo = servo
        self.rc_filter = rc_filter
        names, T = dof_matrix(vt, "horizontal")
        self.actuators, self.T = names, T
        self.Tp = np.linalg.pinv(T)
        self.dofs = GROUPS["horizontal"]
        gains = [vt.gain_scales({"x": "horizontal", "twist": "twist"}[d]) for d in self.dofs]
        self.g = np.array([g for g, _, _ in gains])
        self.kp = np.array([servo.k_p * p for _, p, _ in gains])
        self.kv = np.array([servo.k_v * r for _, _, r in gains])
        Ps = self.valve.supply_pressure
        # C.14 at full spool and the rated drop gives Cv·x_vm; work with spool fraction u
        drop = self.valve.rated_drop or Ps
        self.cv = math.sqrt(2) * self.valve.rated_flow / math.sqrt(drop)
        k_q0 = self.cv / math.sqrt(2) * math.sqrt(Ps)  # C.17 at P_L = 0, per unit spool
        self.k_a = servo.k_t / k_q0  # spool fraction per metre of drive
        self.c_ip = servo.k_ct  # internal leakage = B.5 flow-pressure coefficient
        self.v0 = servo.volume / 2  # each chamber at mid stroke (C.8-C.9)
        self.state_names = tuple([f"P1_{a}" for a in names] + [f"P2_{a}" for a in names]
                                 + [f"Pf_{d}" for d in self.dofs])

    def bind(self, actuator_names: tuple[str, ...]) -> None:
        self.idx = np.array([actuator_names.index(a) for a in self.actuators])
        self.n_all = len(actuator_names)
        self.reset()

    def reset(self) -> None:
        Ps = self.valve.supply_pressure
        k = len(self.actuators)
        self.p1 = np.full(k, Ps / 2)
        self.p2 = np.full(k, Ps / 2)
        self.pf = np.zeros(len(self.dofs))
        self.prev = None
        self.spool = np.zeros(k)

    # -- physics ------------------------------------------------------------------------
    def _beta(self, p: np.ndarray) -> np.ndarray:
        r = self.valve.air_ratio
        if r == 0:
            return np.full_like(p, self.servo.beta)
        return 1.0 / (1.0 / self.servo.beta + r / (1.4 * (np.maximum(p, 0.0) + ATM)))

    def _flows(self, u: np.ndarray, p1: np.ndarray, p2: np.ndarray) -> tuple[np.ndarray, ...]:
        """Orifice flows into chamber 1 and out of chamber 2 (C.1-C.4), u = spool fraction."""
        Ps, cv = self.valve.supply_pressure, self.cv
        p1c, p2c = np.clip(p1, 0.0, Ps), np.clip(p2, 0.0, Ps)
        pos = u >= 0
        q1 = np.where(pos, cv * u * np.sqrt(Ps - p1c), cv * u * np.sqrt(p1c))
        q2 = np.where(pos, cv * u * np.sqrt(p2c), cv * u * np.sqrt(Ps - p2c))
        return q1, q2

    def _rates(self, u, p1, p2, x, v):
        q1, q2 = self._flows(u, p1, p2)
        A = self.servo.area
        leak = self.c_ip * (p1 - p2)
        V1, V2 = self.v0 + A * x, self.v0 - A * x
        dp1 = (q1 - leak - A * v) * self._beta(p1) / V1
        dp2 = (leak - q2 + A * v) * self._beta(p2) / V2
        return dp1, dp2

    def _spool(self, x, v, p1, p2, pf, c):
        q = self.Tp @ x
        qd = self.Tp @ v
        e = np.array([c[DOFS.index(d)] for d in self.dofs]) - q
        pfb = pf if self.rc_filter else self.Tp @ (p1 - p2)
        drive = self.T @ (self.g * (e - self.kp * pfb - self.kv * qd))
        return np.clip(self.k_a * drive, -1.0, 1.0)  # spool stroke limit x_vm

    def step(self, dt: float, s: np.ndarray, c: np.ndarray) -> np.ndarray:
        n = self.n_all
        x, v = s[:n][self.idx], s[n:][self.idx]
        if self.prev is None:
            self.prev = (x.copy(), c.copy())
        x0, c0 = self.prev
        rc = self.servo.rc
        p1, p2, pf = self.p1, self.p2, self.pf
        h = dt / 2
        for j in range(2):  # two Heun substeps over [t_{k-1}, t_k]
            a0, a1 = j / 2, (j + 1) / 2
            xa, xb = x0 + (x - x0) * a0, x0 + (x - x0) * a1
            ca, cb = c0 + (c - c0) * a0, c0 + (c - c0) * a1
            ua = self._spool(xa, v, p1, p2, pf, ca)
            d1a, d2a = self._rates(ua, p1, p2, xa, v)
            dfa = -pf / rc + self.Tp @ (d1a - d2a)
            p1p, p2p, pfp = p1 + h * d1a, p2 + h * d2a, pf + h * dfa
            ub = self._spool(xb, v, p1p, p2p, pfp, cb)
            d1b, d2b = self._rates(ub, p1p, p2p, xb, v)
            dfb = -pfp / rc + self.Tp @ (d1b - d2b)
            p1 = p1 + h / 2 * (d1a + d1b)
            p2 = p2 + h / 2 * (d2a + d2b)
            pf = pf + h / 2 * (dfa + dfb)
        Ps = self.valve.supply_pressure
        self.p1, self.p2, self.pf = np.clip(p1, 0, Ps), np.clip(p2, 0, Ps), pf
        self.prev = (x.copy(), c.copy())
        self.spool = self._spool(x, v, self.p1, self.p2, self.pf, c)
        force = self.servo.area * (self.p1 - self.p2)
        if self.valve.friction:
            force = force - self.valve.friction * np.tanh(v / self.valve.friction_velocity)
        return force
