"""The horizontal actuators stepped by the compiled hydraulic element
(`vtable.hydraulics.element`): the same law as the linear controllers, with the stages
effects added (`vtable.hydraulics.stage`: valve, flow, pressure, feedback and force laws)
compiled into it (`vtable.hydraulics.compose`) — the virtual table's side of the servo
effects and of `--valve nonlinear`."""

from __future__ import annotations

import numpy as np

from vtable.controllers.base import DOFS
from vtable.hydraulics.element import PISTON_AREA
from vtable.hydraulics.law import ServoLaw, StageUse, group_law
from vtable.params.table import ServoConstants
from vtable.params.virtual import VirtualTable


class HydraulicServo:
    """H1-H3 with the horizontal and twist DOF controllers: `law` (default: the table's
    group law with `hydraulics`, one actuator's constants, and `stages`)."""

    def __init__(self, vt: VirtualTable, hydraulics: ServoConstants | None = None,
                 stages: tuple[StageUse, ...] = (), law: ServoLaw | None = None) -> None:
        law = law or group_law(vt, "horizontal", hydraulics, stages=stages)
        self.law = law
        self.actuators = law.actuators
        self.T, self.Tp, self.g, self.kp, self.kv = law.kernel()
        self.element = law.composition()
        self.sp = law.vector(self.element)
        self.cidx = np.array([DOFS.index(d) for d in law.dofs])
        names = self.element.state_names()
        self.state_names = tuple(f"{k}_{a}" for a in self.actuators for k in names)

    def bind(self, actuator_names: tuple[str, ...]) -> None:
        self.idx = np.array([actuator_names.index(a) for a in self.actuators])
        self.n_all = len(actuator_names)
        self.reset()

    def reset(self) -> None:
        self.z = np.zeros(len(self.actuators) * self.element.ns)
        self.prev = None
        self.force = np.zeros(len(self.actuators))

    def step(self, dt: float, s: np.ndarray, c: np.ndarray) -> np.ndarray:
        x, v = s[self.idx], s[self.n_all + self.idx]
        cd = c[self.cidx]
        if self.prev is None:
            self.prev = (x, v, cd)
        x0, v0, c0 = self.prev
        self.element.module.servo_step(self.z, x0, x, v, v0, c0, cd, dt, self.T, self.Tp,
                                       self.g, self.kp, self.kv, self.sp, self.force)
        self.prev = (x, v, cd)
        return self.force.copy()

    def pressure_force(self) -> np.ndarray:
        """Each actuator's piston force A·P_L (eq 6.3) at the end of the last step: what a
        ΔP transducer reads, before the force stages (friction) the applied force has."""
        return self.sp[PISTON_AREA] * self.z[::self.element.ns]
