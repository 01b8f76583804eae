"""The DOF servo law of the table's controllers (eqs 6.1-6.4, B.4-B.6), written once.

A group of n actuators (extension x_i along its own line) under d DOF controllers:
T (n x d) is the extension of each actuator per unit DOF motion, q = T⁺x the DOF
displacement, P̄ = T⁺P the DOF pressure, and per DOF j the gains g_j (loop gain), k_p,j
(ΔP feedback) and k_v,j (velocity):

    u_i = Σ_j T_ij g_j [ (q_c,j - q_j) - k_p,j P̄f_j - k_v,j q̇_j ]          (eqs 6.1, 6.4)
    (V_i/4β) Ṗ_i = k_t u_i - k_ct P_i - A ẋ_i,   F_i = A P_i               (eqs 6.2-6.3)

A law may carry stages (`stage.Stage`, each with its named parameters: an effect's
physics in the element — the RC filter of eq B.4 on the ΔP feedback is one); `composition`
compiles the element for them and `vector` lays out their parameters. `linear_blocks`
gives the matrices of the linear loop (the linear controllers): the compiled element's
rates on unit states, so the law is written once, in the element; `kernel`
the inputs of the compiled element (`element.servo_rates`), `lumped` one equivalent
actuator for one DOF, and `dof_loop` the single-state loop of one DOF under symmetric
pressures (the reduced model's pitch loop). For identical actuators and symmetric motion
each DOF loop reduces to eq 6.5a with the mass per actuator M_d/ΣT_ij².
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from vtable.errors import VtableError
from vtable.hydraulics.compose import Composition, checked, composition
from vtable.hydraulics.stage import Stage
from vtable.params.table import ServoConstants

#: a stage with its named parameters (SI)
StageUse = tuple[Stage, dict[str, float]]

GROUP_DOFS = {"horizontal": ("x", "twist"), "vertical": ("z", "pitch", "roll")}
#: the knob direction (Table 3.2) of each DOF controller
DIRECTION = {"x": "horizontal", "twist": "twist", "z": "vertical", "pitch": "pitch",
             "roll": "roll"}


@dataclass(frozen=True)
class LinearBlocks:
    """ż = A z + Bx x + Bv ẋ + Bc q_c, F = C z; z = each actuator's states
    (`ServoLaw.state_names`)."""

    A: np.ndarray
    Bx: np.ndarray
    Bv: np.ndarray
    Bc: np.ndarray
    C: np.ndarray


@dataclass(frozen=True)
class ServoLaw:
    """eqs 6.1-6.4 for one actuator group (see the module docstring)."""

    actuators: tuple[str, ...]
    dofs: tuple[str, ...]
    T: np.ndarray
    g: np.ndarray
    k_p: np.ndarray
    k_v: np.ndarray
    hydraulics: ServoConstants
    stages: tuple[StageUse, ...] = ()

    def __post_init__(self) -> None:
        if self.dofs[0] != "x" and any(s.kind == "control" for s, _ in self.stages):
            raise VtableError(f"a control stage drives the horizontal DOF x, and this law's "
                              f"first DOF is {self.dofs[0]} ({', '.join(self.dofs)})")

    @property
    def linear(self) -> bool:
        """Whether every stage is linear (the loop is then a linear system)."""
        return all(s.linear for s, _ in self.stages)

    def composition(self, extra: Sequence[Callable] = (), elements: Sequence = (),
                    switchable: Sequence[Stage] = ()) -> Composition:
        """The compiled element of this law's stages (`compose.composition`), with force
        elements' laws (`compose.ElementLaw`) when given; `switchable` stages are written
        behind flags (this law's own among them switched on by `vector`)."""
        fixed = [s for s, _ in self.stages if not any(s is t for t in switchable)]
        return composition(fixed, extra, elements, switchable)

    def check(self) -> None:
        """A one-line error where this law's stages cannot make one element
        (`compose.checked`); nothing compiled, written or imported."""
        checked([s for s, _ in self.stages])

    def vector(self, comp: Composition) -> np.ndarray:
        """The element's parameters for `comp` (this law's composition)."""
        given = {s.name: p for s, p in self.stages}
        return comp.vector(self.hydraulics, [given.get(s.name) for s in comp.stages])

    def with_stages(self, stages: Sequence[StageUse]) -> ServoLaw:
        return replace(self, stages=tuple(stages))

    def state_names(self) -> tuple[str, ...]:
        """The states of `linear_blocks`, in its order."""
        names = self.composition().state_names()
        return tuple(f"{k}_{a}" for a in self.actuators for k in names)

    def state_units(self) -> tuple[str, ...]:
        """The units of `state_names`."""
        return tuple(self.composition().state_units()) * len(self.actuators)

    @property
    def Tp(self) -> np.ndarray:
        return _pinv(self.T.tobytes(), self.T.shape).copy()

    def kernel(self) -> tuple[np.ndarray, ...]:
        """(T, T⁺, g, k_p, k_v) for `element.servo_rates`."""
        return (np.ascontiguousarray(self.T), np.ascontiguousarray(self.Tp), self.g.copy(),
                self.k_p.copy(), self.k_v.copy())

    def linear_blocks(self) -> LinearBlocks:
        """The linear loop's matrices (every stage linear): the compiled element's rates
        (`element.servo_rates` with this law's stages) on unit states and inputs, exact
        for a linear loop; states per actuator as `Composition.state_names`."""
        if not self.linear:
            raise VtableError("the loop has a nonlinear stage: "
                              f"{', '.join(s.name for s, _ in self.stages if not s.linear)}")
        comp = self.composition()
        T, Tp, g, kp, kv = self.kernel()
        sp = self.vector(comp)
        n, d = T.shape
        nz = n * comp.ns
        cols = {"z": nz, "x": n, "v": n, "c": d}
        out = {k: np.zeros((nz, m)) for k, m in cols.items()}
        C = np.zeros((n, nz))
        dz, f = np.zeros(nz), np.zeros(n)
        for k, m in cols.items():
            for j in range(m):
                u = {q: np.zeros(cols[q]) for q in cols}
                u[k][j] = 1.0
                comp.module.servo_rates(u["z"], u["x"], u["v"], u["c"], T, Tp, g, kp, kv, sp,
                                        dz, f)
                out[k][:, j] = dz
                if k == "z":
                    C[:, j] = f
                elif np.any(f):
                    raise VtableError("a linear stage makes the force depend on the motion")
        return LinearBlocks(out["z"], out["x"], out["v"], out["c"], C)

    def fastest_rate(self) -> float:
        """The linear loop's fastest rate max |λ(A)| (1/s) of `linear_blocks` with the
        motion held: what bounds an explicit integrator's step (RK4: |λ| h < 2.8)."""
        return float(np.max(np.abs(np.linalg.eigvals(self.linear_blocks().A))))

    def lumped(self, dof: str) -> ServoLaw:
        """The actuators acting on `dof` alone as one equivalent actuator (T = 1): the
        reduced model's horizontal actuator. Needs Σ_i T_ij² = n (unit levers)."""
        j = self.dofs.index(dof)
        n = len(self.actuators)
        stages = tuple((s, {k: v * n if k in s.extensive else v for k, v in p.items()})
                       for s, p in self.stages)
        return ServoLaw((f"{dof} (lumped)",), (dof,), np.ones((1, 1)), self.g[[j]],
                        self.k_p[[j]], self.k_v[[j]], self.hydraulics.lumped(n), stages)

    def dof_loop(self, dof: str) -> tuple[float, float, float, float]:
        """One DOF under symmetric pressures P_i = T_ij p (no stage, zero command):
        ṗ = a p + b_q q + b_v q̇, generalized force on q = f·p. Returns (a, b_q, b_v, f),
        the DOF's projection (T⁺_j, T_j) of `linear_blocks`."""
        j = self.dofs.index(dof)
        if self.stages:
            raise ValueError(f"the {dof} loop has stages: not a single-state loop")
        key = (dof, self.dofs, self.T.tobytes(), self.T.shape, self.g.tobytes(),
               self.k_p.tobytes(), self.k_v.tobytes(), self.hydraulics)
        hit = _DOF_LOOPS.get(key)
        if hit is not None:
            return hit
        b = self.linear_blocks()
        t, tp = self.T[:, j], self.Tp[j]
        out = (float(tp @ b.A @ t), float(tp @ b.Bx @ t), float(tp @ b.Bv @ t),
               float(t @ b.C @ t))
        if len(_DOF_LOOPS) >= 64:  # a fit asks for the same few loops thousands of times
            with contextlib.suppress(RuntimeError, KeyError, StopIteration):  # threads
                _DOF_LOOPS.pop(next(iter(_DOF_LOOPS)))  # share it: left to the other
        _DOF_LOOPS[key] = out
        return out

    def with_hydraulics(self, hydraulics: ServoConstants) -> ServoLaw:
        return replace(self, hydraulics=hydraulics)


_DOF_LOOPS: dict[tuple, tuple[float, float, float, float]] = {}


@functools.lru_cache(maxsize=64)
def _pinv(data: bytes, shape: tuple[int, ...]) -> np.ndarray:
    """T⁺ of the actuator matrix T (given by value: a fit builds the same few T's
    thousands of times); read-only."""
    out = np.linalg.pinv(np.frombuffer(data).reshape(shape))
    out.flags.writeable = False
    return out


def dof_matrix(vt, kind: str) -> tuple[tuple[str, ...], np.ndarray]:
    """Actuator names of a group and T (n_act x n_dof): extension per unit DOF motion.

    Small rotations about the pivot: twist ψ moves H_i (at y_i) by -y_i ψ along x; pitch θ
    moves V_i (at x_i) by -x_i θ up; roll φ moves V_i by +y_i φ up.
    """
    acts = vt.group(kind)
    names = tuple(a.name for a in acts)
    if kind == "horizontal":
        T = np.array([[1.0, -a.slab_point[1]] for a in acts])
    else:
        T = np.array([[1.0, a.slab_point[1], -a.slab_point[0]] for a in acts])
        T = T[:, [0, 2, 1]]  # columns z, pitch, roll
    return names, T


def group_law(vt, kind: str, hydraulics: ServoConstants | None = None,
              stages: Sequence[StageUse] = ()) -> ServoLaw:
    """The law of the table's `kind` group ("horizontal" or "vertical") at its knob
    settings: g, k_p, k_v of each DOF = the knob scales (`VirtualTable.gain_scales`) times
    the group's reference constants; `hydraulics` defaults to the table's; `stages` (one
    actuator's) enter its element."""
    if hydraulics is None:
        hydraulics = vt.horizontal_servo if kind == "horizontal" else vt.vertical_servo
    names, T = dof_matrix(vt, kind)
    keep = [j for j, d in enumerate(GROUP_DOFS[kind]) if d in vt.dofs]
    dofs = tuple(GROUP_DOFS[kind][j] for j in keep)
    T = T[:, keep]
    scales = np.array([vt.gain_scales(DIRECTION[d]) for d in dofs])
    return ServoLaw(names, dofs, T, scales[:, 0], hydraulics.k_p * scales[:, 1],
                    hydraulics.k_v * scales[:, 2], hydraulics, tuple(stages))
