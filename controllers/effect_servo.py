"""The horizontal actuators with the servo effects of the catalog (RC filter, orifice
flow, friction, flow saturation, spool lag, entrained air), stepped by the same compiled
kernel as the diagnosis's reduced model (vtable.effects.kernel), and the specimen's
amplitude-dependent (quadratic) damper."""

from __future__ import annotations

import numpy as np

from vtable.controllers.base import DOFS
from vtable.controllers.servo import GROUPS, dof_matrix
from vtable.effects.kernel import servo_step
from vtable.params.virtual import VirtualTable


class KernelServo:
    """H1-H3 with the horizontal and twist DOF controllers; `sp` is the kernel's
    per-actuator parameter vector (vtable.effects.physics.servo_vector)."""

    def __init__(self, vt: VirtualTable, sp: np.ndarray) -> None:
        names, T = dof_matrix(vt, "horizontal")
        self.actuators, self.T, self.Tp = names, T, np.linalg.pinv(T)
        self.sp = np.asarray(sp, dtype=float)
        dofs = GROUPS["horizontal"]
        self.cidx = np.array([DOFS.index(d) for d in dofs])
        scales = [vt.gain_scales({"x": "horizontal", "twist": "twist"}[d]) for d in dofs]
        self.g = np.array([s[0] for s in scales])
        self.kp = np.array([self.sp[5] * s[1] for s in scales])
        self.kv = np.array([self.sp[6] * s[2] for s in scales])
        self.state_names = tuple(f"{k}_{a}" for a in names for k in ("P", "Pf", "q"))

    def bind(self, actuator_names: tuple[str, ...]) -> None:
        self.idx = np.array([actuator_names.index(a) for a in self.actuators])
        self.n_all = len(actuator_names)
        self.reset()

    def reset(self) -> None:
        self.z = np.zeros((len(self.actuators), 3))
        self.prev = None
        self.force = np.zeros(len(self.actuators))

    def step(self, dt: float, s: np.ndarray, c: np.ndarray) -> np.ndarray:
        x, v = s[self.idx], s[self.n_all + self.idx]
        cd = c[self.cidx]
        if self.prev is None:
            self.prev = (x, v, cd)
        x0, v0, c0 = self.prev
        servo_step(self.z, x0, x, v, v0, c0, cd, dt, self.T, self.Tp, self.g, self.kp, self.kv,
                   self.sp, self.force)
        self.prev = (x, v, cd)
        return self.force.copy()


class QuadraticDamper:
    """F = -c₂|ẋ|ẋ on the structure's storey slides (actuators S1, S2, ...)."""

    def __init__(self, c2: float, actuators: tuple[str, ...]) -> None:
        self.c2, self.actuators = c2, tuple(actuators)

    def bind(self, actuator_names: tuple[str, ...]) -> None:
        self.idx = np.array([actuator_names.index(a) for a in self.actuators])
        self.n_all = len(actuator_names)
        self.reset()

    def reset(self) -> None:
        self.v_prev = None

    def step(self, dt: float, s: np.ndarray, c: np.ndarray) -> np.ndarray:
        v = s[self.n_all + self.idx]
        vp = v if self.v_prev is None else self.v_prev
        self.v_prev = v
        vh = 1.5 * v - 0.5 * vp  # velocity at t_k (see LinearController.discrete)
        return -self.c2 * np.abs(vh) * vh
