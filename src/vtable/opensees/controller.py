"""An OpenSees specimen on the virtual table: the piece that steps the model
(`vtable.opensees.stepper`) with the platen, as the simulator steps its controllers, and
returns its reactions to it (the specimen owns its step hook, as a dm_control `Entity`
does).

It drives no actuator. Given the simulator's MuJoCo model and data (`attach`), each
control step it reads the platen (the slab's joints: the accelerations of the two steps
before, from which this step's are predicted, and the pitch now), advances the model one
step
and applies the model's wrench on the platen at the actuator line's centre as an applied
force (``qfrc_applied``, through ``mj_applyFT``), for MuJoCo's step that follows. It keeps
every step's floor motion and wrench (`history`).
"""

from __future__ import annotations

import mujoco
import numpy as np

from vtable.opensees.model import OpenSeesModel
from vtable.opensees.stepper import OpenSeesStepper

#: the most nodes whose every displacement is kept for drawing (memory: 2 floats a node
#: a step)
MAX_DRAWN_NODES = 500


class OpenSeesController:
    """The model `model` at `depth` (m, the actuator line below the table top), stepped
    at `dt` (the control step)."""

    actuators: tuple[str, ...] = ()

    def __init__(self, model: OpenSeesModel, depth: float, dt: float) -> None:
        self.stepper = OpenSeesStepper(model, depth, dt)
        self.model = model
        #: keep every node's displacement (the deformed shape drawn) for models this small
        self.draw = len(model.nodes) <= MAX_DRAWN_NODES

    def attach(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """The simulator's model and data: the slab's body and joints."""
        self.m, self.d = m, d
        self.slab = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "slab")

        def dof(name: str) -> int | None:
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
            return None if j < 0 else int(m.jnt_dofadr[j])

        self.jx, self.jz, self.jp = dof("x"), dof("z"), dof("pitch")
        jp = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "pitch")
        self.qp = None if jp < 0 else int(m.jnt_qposadr[jp])

    def bind(self, actuator_names: tuple[str, ...]) -> None:
        pass

    def reset(self) -> None:
        self.stepper.start()
        self.k = 0
        self.a_before = np.zeros(3)
        self.rows: list[np.ndarray] = []
        self.nodes: list[np.ndarray] = []

    def _acc(self, i: int | None) -> float:
        return 0.0 if i is None else float(self.d.qacc[i])

    def step(self, dt: float, s: np.ndarray, c: np.ndarray) -> np.ndarray:
        d = self.d
        last = np.array([self._acc(self.jx), self._acc(self.jz), self._acc(self.jp)])
        theta = 0.0 if self.qp is None else float(d.qpos[self.qp])
        if self.k > 0:  # to this step, under the platen's predicted accelerations
            pred = 2 * last - self.a_before if self.k > 1 else last
            self.stepper.step(*pred, theta)
            self.a_before = last
        f_xi, f_eta, m_y = self.stepper.wrench()
        R = d.xmat[self.slab].reshape(3, 3)
        d.qfrc_applied[:] = 0.0
        mujoco.mj_applyFT(self.m, d, R @ np.array([f_xi, 0.0, f_eta]),
                          R @ np.array([0.0, m_y, 0.0]), d.xpos[self.slab].copy(), self.slab,
                          d.qfrc_applied)
        u, acc = self.stepper.floors()
        self.rows.append(np.concatenate([u, acc, [f_xi, f_eta, m_y]]))
        if self.draw:
            self.nodes.append(self.stepper.u[:, :2].astype(np.float32))
        self.k += 1
        return np.zeros(0)

    def history(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        """The recorded steps `rows`: each floor's relative displacement and acceleration
        (n_t, n_floors; m, m/s²), the wrench on the platen (F_ξ, F_η, M_y; N, N m) and,
        for a model of at most `MAX_DRAWN_NODES` nodes, every node's relative displacement
        (n_t, n_nodes, 2; m)."""
        h = np.asarray(self.rows)[rows]
        n = len(self.model.floors)
        out = {"u": h[:, :n], "a": h[:, n:2 * n], "wrench": h[:, 2 * n:]}
        if self.draw:
            out["nodes"] = np.asarray(self.nodes)[rows]
        return out
