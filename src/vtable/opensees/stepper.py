"""Stepping an OpenSees model with the platen (the virtual table's side is
`vtable.opensees.controller`).

The model moves with the platen, in the platen's frame (origin O at the centre of the
horizontal actuator line, ξ along the shaking direction, η up, pitch θ positive when the
+ξ end goes down; X = ξ, Y = η − d for the model, d the actuator line's depth below the
table top). Its fixed DOFs (its base, and any other ``ops.fix``) move with the platen:
the platen's motion is imposed there. Its relative displacements u obey, for a node of
masses m_x, m_y, I at (ξ, η) and small θ,

    M ü + (damping, resisting forces)(u, u̇) = P,
    P_x = m_x (g θ − a_x − θ̈ η),  P_y = −m_y (a_z − θ̈ ξ) − m_y g,  P_φ = I θ̈

(the platen's acceleration at the node and gravity along the tilted platen; the weight
−m_y g is applied first, by a static gravity analysis; OpenSees' φ turns from X to Y, the
opposite sense to θ). The dynamic loads are parameters of one pattern, updated every
step; OpenSees integrates (Newmark, average acceleration).

What the model returns to the platen. Each free DOF j carries P_j − m_j ü_j: by OpenSees'
equilibrium at the step's end these are the forces its elements and dampers transmit, a
function of the model's state, so a free mass reaches the platen only through the
structure, as it does in the lab. A mass on a fixed DOF moves with the platen: the
multibody table carries it as a welded body (`OpenSeesModel.welded`: MuJoCo gives its
inertia and weight exactly at each step); where that node is free in its other
translation, that direction's welded inertia and weight are taken back,
+m_w (a − g)_j, so the model's dynamics stay the only ones there. Forces act at the
nodes' displaced positions (the moment M_y about O included: Σ η' F_ξ − ξ' F_η).

The platen's accelerations at the step being solved are not known yet (they depend on
what the model returns): the loads use the prediction 2 a_{k−1} − a_{k−2} from the two
before (on the Table 9.2-like building of tests/models/test_opensees.py, the table's pitch
acceleration was 56 % off the converged solution at 1 kHz with a_{k−1}, 4 % with the
prediction; 0.05 % at 8 kHz).
"""

from __future__ import annotations

import numpy as np

from vtable.errors import VtableError
from vtable.opensees.library import last_message, opensees
from vtable.opensees.model import OpenSeesModel, build, read
from vtable.units import G

#: tags vtable's own OpenSees objects use (far above a model's usual tags)
TAG = 970_000
GRAVITY_STEPS = 10
TOLERANCE = 1e-10  # NormDispIncr, in the model's length unit
MAX_ITER = 50
SUBSTEPS = 10  # a step that does not converge is tried again in this many substeps


class OpenSeesStepper:
    """One OpenSees model stepped at `dt` with the platen (see the module docstring)."""

    def __init__(self, model: OpenSeesModel, depth: float, dt: float) -> None:
        self.model, self.depth, self.dt = model, depth, dt
        m = model
        self.free = ~m.fixed & (m.masses > 0)
        self.xi = m.coords[:, 0]
        self.eta = m.coords[:, 1] + depth
        self.m_w = m.welded
        self.floor_idx = [[m.index(t) for t in f] for f in m.floors]
        self.f_u, self.l_u = m.force_unit, m.length_unit
        # the load on each DOF in the model's units per SI newton (rotation: per N m)
        self.to_model = np.array([1 / self.f_u, 1 / self.f_u, 1 / (self.f_u * self.l_u)])
        self.t = 0.0

    def start(self) -> None:
        """Build the model afresh (`build(ops)`), apply gravity statically, and set up the
        platen loads and the transient analysis."""
        ops = self.ops = opensees()
        m = self.model
        read(m.path, ops, build(m.path, ops))  # the same model, checked again
        ops.timeSeries("Linear", TAG)
        ops.pattern("Plain", TAG, TAG)
        self.p_static = np.zeros((len(m.nodes), 3))
        self.p_static[:, 1] = np.where(self.free[:, 1], -m.masses[:, 1] * G, 0.0)
        for i in np.flatnonzero(self.p_static[:, 1]):
            ops.load(m.nodes[i], 0.0, self.p_static[i, 1] / self.f_u, 0.0)
        self._analysis(static=True)
        if ops.analyze(GRAVITY_STEPS) != 0:
            raise VtableError(f"{m.path}: OpenSees did not converge under the model's own "
                              f"weight (gravity analysis; OpenSees: {last_message()})")
        ops.loadConst("-time", 0.0)
        ops.wipeAnalysis()
        ops.timeSeries("Constant", TAG + 1, "-factor", 1.0)
        ops.pattern("Plain", TAG + 1, TAG + 1)
        loaded = np.flatnonzero(self.free.any(axis=1))
        for i in loaded:
            ops.load(m.nodes[i], 0.0, 0.0, 0.0)
        self.params = []  # (parameter tag, node index, dof)
        tag = TAG
        for i in loaded:
            for dof in np.flatnonzero(self.free[i]):
                ops.parameter(tag, "pattern", TAG + 1, "loadAtNode", m.nodes[i], int(dof) + 1)
                self.params.append((tag, int(i), int(dof)))
                tag += 1
        self._analysis(static=False)
        self.t = 0.0
        self.u0 = self._read("nodeDisp")  # the state under gravity: u counts from it
        self.u = np.zeros((len(m.nodes), 3))  # relative displacements (SI)
        self.a = np.zeros((len(m.nodes), 3))  # relative accelerations (SI)
        self.p = self.p_static.copy()  # the loads now (SI)
        self.platen = np.zeros(4)  # (a_x, a_z, θ̈, θ) of the loads now

    def _analysis(self, static: bool) -> None:
        ops = self.ops
        ops.constraints("Transformation")
        ops.numberer("RCM")
        ops.system("BandGeneral")
        ops.test("NormDispIncr", TOLERANCE, MAX_ITER)
        ops.algorithm("Newton")
        if static:
            ops.integrator("LoadControl", 1.0 / GRAVITY_STEPS)
            ops.analysis("Static")
        else:
            ops.integrator("Newmark", 0.5, 0.25)
            ops.analysis("Transient")

    def _read(self, what: str) -> np.ndarray:
        get = getattr(self.ops, what)
        out = np.array([get(t)[:3] for t in self.model.nodes], dtype=float)
        out[:, :2] *= self.l_u
        return out

    def loads(self, a_x: float, a_z: float, alpha: float, theta: float) -> np.ndarray:
        """The loads P (n, 3; SI) of the module docstring, on the free DOFs."""
        m = self.model.masses
        p = np.empty_like(m)
        p[:, 0] = m[:, 0] * (G * theta - a_x - alpha * self.eta)
        p[:, 1] = -m[:, 1] * (a_z - alpha * self.xi)
        p[:, 2] = m[:, 2] * alpha
        return np.where(self.free, p + self.p_static, 0.0)

    def step(self, a_x: float, a_z: float, alpha: float, theta: float) -> None:
        """Advance one `dt` under the platen's accelerations a_x, a_z (m/s²), θ̈ = alpha
        (rad/s²) and its pitch θ (rad) at the step's end (the loads P)."""
        ops = self.ops
        self.p = self.loads(a_x, a_z, alpha, theta)
        self.platen = np.array([a_x, a_z, alpha, theta])
        dyn = (self.p - self.p_static) * self.to_model
        for tag, i, dof in self.params:
            ops.updateParameter(tag, float(dyn[i, dof]))
        if ops.analyze(1, self.dt) != 0 and ops.analyze(SUBSTEPS, self.dt / SUBSTEPS) != 0:
            raise VtableError(f"{self.model.path}: OpenSees did not converge at t = "
                              f"{self.t:.3f} s (the model's own analysis: try a finer "
                              "control step or a more robust model; OpenSees: "
                              f"{last_message()})")
        self.t += self.dt
        self.u = self._read("nodeDisp") - self.u0
        self.a = self._read("nodeAccel")

    def wrench(self) -> tuple[float, float, float]:
        """(F_ξ, F_η, M_y) the model returns to the platen at O, SI (the module
        docstring), for the loads of the last step."""
        m, u = self.model.masses, self.u
        f = np.where(self.free, self.p - m * self.a, 0.0)
        a_x, a_z, alpha, theta = self.platen
        # welded nodes free in a translation: that direction's welded inertia and weight
        # taken back, +m_w (a − g) at the node (a: the platen's there, predicted)
        back = np.stack([a_x + alpha * self.eta - G * theta,
                         a_z - alpha * self.xi + G], axis=1) * self.m_w[:, None]
        f[:, :2] += np.where(self.free[:, :2] & (self.m_w > 0)[:, None], back, 0.0)
        xi, eta = self.xi + u[:, 0], self.eta + u[:, 1]
        moment = eta * f[:, 0] - xi * f[:, 1] - f[:, 2]
        # the welded masses' weight and inertia, moved with their free translation
        moment += self.m_w * (u[:, 0] * (G + a_z - alpha * self.xi)
                              + u[:, 1] * (G * theta - a_x - alpha * self.eta)) * (
            self.free[:, 0] | self.free[:, 1])
        return float(f[:, 0].sum()), float(f[:, 1].sum()), float(moment.sum())

    def floors(self) -> tuple[np.ndarray, np.ndarray]:
        """Each floor's mean relative horizontal displacement and acceleration (SI)."""
        return (np.array([self.u[ix, 0].mean() for ix in self.floor_idx]),
                np.array([self.a[ix, 0].mean() for ix in self.floor_idx]))
