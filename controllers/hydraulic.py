"""The horizontal actuators stepped by the compiled hydraulic element
(`vtable.hydraulics.element`): the same law as the linear controllers with the appendix C
options (orifice flow, rated-flow cap, spool lag, entrained air, friction) switched by
their named parameters — the virtual table's side of the servo effects and of
`--valve nonlinear`."""

from __future__ import annotations

import numpy as np

from vtable.controllers.base import DOFS
from vtable.hydraulics.element import HydraulicParams, servo_step
from vtable.hydraulics.law import group_law
from vtable.params.virtual import VirtualTable


class HydraulicServo:
    """H1-H3 with the horizontal and twist DOF controllers; `hydraulics` are one
    actuator's constants and options (default: the table's)."""

    def __init__(self, vt: VirtualTable, hydraulics: HydraulicParams | None = None) -> None:
        law = group_law(vt, "horizontal", hydraulics, rc_dofs=("x", "twist"))
        self.law = law
        self.actuators = law.actuators
        self.T, self.Tp, self.g, self.kp, self.kv = law.kernel()
        self.sp = law.hydraulics.vector()
        self.cidx = np.array([DOFS.index(d) for d in law.dofs])
        self.state_names = tuple(f"{k}_{a}" for a in self.actuators for k in ("P", "Pf", "q"))

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
