"""The fast reduced model the diagnosis fits, composed from a small assembly.

`ReducedAssembly` starts from the planar table of report chapter 7 — the platen in x
carrying the specimen's storeys, one equivalent horizontal actuator under the DOF servo
law (`vtable.hydraulics`), mechanics from the same assembly as the virtual table's linear
model (`models.linear_table.mechanics`: the platen cannot pitch until an effect frees
it) — and offers effects the vocabulary of `vtable.effects.base.Assembly`: degrees of
freedom, springs, linear control loops, the hydraulic element's stages, force
elements (a law of a relative motion, compiled with numba when it can be, else run as
Python) and output filters. `ReducedModel` integrates what they made
(`reduced_kernel.simulate_reduced`) and predicts a run's channels from its command.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np

from vtable._numba import first_compile
from vtable.analytic.hold import first_order_hold
from vtable.analytic.structure import storey_channels, storey_masses
from vtable.controllers.force_law import law_params
from vtable.effects.registry import stock_stages
from vtable.errors import VtableError, interrupted
from vtable.hydraulics import group_law
from vtable.hydraulics.compose import ElementLaw, counted
from vtable.hydraulics.element import PISTON_AREA
from vtable.hydraulics.stage import Stage, add_stage
from vtable.hydraulics.table_stages import table_stages
from vtable.interpolate import upsampled
from vtable.models import physics as phys
from vtable.models import reduced_unrolled as unrolled
from vtable.models.modal import ModalOutputs, filtered
from vtable.models.reduced_kernel import (
    KERNELS,
    law_where,
    linear_system,
    python_elements,
    simulate_linear,
    simulate_reduced,
    simulate_reduced_python,
)
from vtable.models.reduced_parts import (
    base_servo,
    lumped_law,
    mechanics_on,
    pitch_loop,
    table_view,
)
from vtable.models.stiffness import needed_stiffness
from vtable.params.virtual import VirtualTable
from vtable.runs.model import Run
from vtable.tables.eerc import split_rocking, virtual_table

SIM_DT = 0.0025  # s: the largest integration step (a run step is divided until below it)
LINEAR_PATH = True  # step linear models exactly (False: RK4 for every model; for tests)

class Histories(NamedTuple):
    """The integrator's histories on the model step `h` (the run step / `up`): the command
    upsampled, the generalized coordinates q, q̇, q̈ (n x coordinates), the lumped
    actuator's force and its load pressure P_L."""

    h: float
    up: int
    x_c: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    force: np.ndarray
    p_l: np.ndarray


class Channels(dict):
    """A reduced model's prediction of a run: its channels by run-format name (SI, each
    array on the run's time grid `t`), as a run's own channels are held; `h` the step the
    model was integrated at."""

    def __init__(self, channels: dict[str, np.ndarray], t: np.ndarray, h: float) -> None:
        super().__init__(channels)
        self.t, self.h = t, h


@dataclass
class ForceElement:
    law: Callable
    a: str
    b: str | None
    params: np.ndarray
    states: int
    names: tuple[str, ...] | None = None  # the law reads p.name (`law_params`)


class ReducedAssembly:
    """The reduced model under construction (see the module docstring). Coordinates are
    named: "x" (the platen at the actuator line), "pitch" once freed, the specimen's
    slides ("x_s", "x_s1", ...), and what effects add."""

    def __init__(self, ph: phys.Physics, vt: VirtualTable) -> None:
        vt, (M, K, C, _, names, slides, pos) = mechanics_on(ph, vt)
        self.vt, self.specimen = vt, ph.specimen
        self._full = (M, K, C, list(names))
        self.storeys = [names[5 + i] for i in range(len(slides))]
        self.active = ["x", *self.storeys]
        self.h_top = float(pos[slides[-1].name][2]) if slides else 0.0
        self.h_floors = [float(pos[b.name][2]) for b in slides]  # h_K, from the bottom
        self.extra: dict[str, float] = {}  # added DOFs: name -> mass
        self.springs: list[tuple[str, str | None, float, float]] = []
        self.structures: list[tuple[str, float, float, float]] = []
        self.loops: list[tuple[str, float, float, float, float]] = []
        self.quadratic: list[tuple[str, float]] = []
        self.elements: list[ForceElement] = []
        #: (fn(x, fs), the channels it applies to or None: all)
        self.filters: list[tuple[Callable, frozenset | None]] = []
        self.moving, self.reaction = "x", None
        self.max_step = SIM_DT
        self.servo = base_servo(ph, vt)
        self.stages: list[tuple[Stage, dict[str, float]]] = []
        self.table = table_view(vt, self.servo.area)
        self.n_actuators = len(vt.group("horizontal"))
        for stage, params in table_stages(vt, rc=False):  # its valve lag, its controller's
            self.add_stage(stage, **params)
        if vt.control is not None:  # a digital controller's own terms (RK4: |λ| h < 2.8)
            rate = group_law(vt, "horizontal", stages=[vt.control.use]).lumped("x") \
                .fastest_rate()
            self.max_step = min(self.max_step, 2.0 / rate)
        if vt.horizontal_servo.damping:  # the platen's viscous damping (a lab's table)
            self.add_spring("x", None, 0.0, vt.horizontal_servo.damping * self.n_actuators)

    # -- the vocabulary ----------------------------------------------------------------
    def add_stage(self, stage: Stage, **params: float) -> None:
        add_stage(self.stages, stage, params)

    def unlock(self, dof: str) -> None:
        phys.check_dof(self.vt, dof)
        if dof not in self.active:
            self.active.insert(1, dof)

    def set_rocking(self, k_theta: float, c_theta: float) -> None:
        """The virtual table's own pitch system: stabilizers retuned to (k_θ, c_θ) plus the
        vertical actuators' pitch DOF loop (one state)."""
        vt = self.vt
        k_s, c_s = split_rocking(k_theta, c_theta, vt)
        d_p = vt.table.geometry.stabilizer_square
        self.add_spring("pitch", None, k_s * d_p**2, c_s * d_p**2)
        a, b_q, b_v, f = pitch_loop(vt)
        self.loops.append(("pitch", a, b_q, b_v, f))

    def add_dof(self, name: str, mass: float) -> None:
        if name in self.extra or name in self.active:
            raise VtableError(f"the reduced model already has a coordinate {name!r}: two "
                              "effects add the same part")
        self.extra[name] = float(mass)
        self.active.append(name)

    def add_spring(self, a: str, b: str | None, stiffness: float, damping: float) -> None:
        self.springs.append((a, b, stiffness, damping))

    def add_structure(self, name: str, mass: float, stiffness: float, damping: float) -> None:
        self.add_dof(name, mass)
        self.add_spring(name, "x", stiffness, damping)
        self.structures.append((name, float(mass), float(stiffness), float(damping)))

    def set_actuator(self, moving: str | None = None, reaction: str | None = None) -> None:
        """What the equivalent actuator pushes (and reacts on): its extension is
        q[moving] - q[reaction]."""
        self.moving = moving or self.moving
        self.reaction = reaction or self.reaction

    def add_reaction_mass(self, name: str, mass: float, stiffness: float,
                          damping: float) -> None:
        self.add_dof(name, mass)
        self.add_spring(name, None, stiffness, damping)
        self.set_actuator(reaction=name)

    def add_opensees(self, spec) -> None:
        raise VtableError("the reduced model cannot hold an OpenSees specimen: only the "
                          "virtual table steps it (vtable simulate)")

    def add_force(self, law: Callable, a: str, b: str | None = None,
                  params: Sequence[float] = (), states: int = 0, mass: float = 0.0,
                  stiffness: float | None = None) -> None:
        """A force element; `stiffness` (N/m, the law's largest slope; worked out from the
        law when left out) on `mass` (kg) sets the integration step below 2/ω (RK4 is
        stable to ωh ≈ 2.8)."""
        if stiffness is None:
            stiffness = needed_stiffness(law, params, states)
        values, names = law_params(params)
        self.elements.append(ForceElement(law, a, b, values, states, names))
        if stiffness > 0 and mass > 0:
            self.max_step = min(self.max_step, 2.0 / math.sqrt(stiffness / mass))

    def insert_at_actuators(self, name: str, mass: float, law: Callable,
                            params: Sequence[float], states: int = 0,
                            stiffness: float | None = None) -> None:
        self.add_dof(name, mass)
        self.set_actuator(moving=name)
        self.add_force(law, name, "x", params, states, mass, stiffness)

    def add_storey_force(self, law: Callable, params: Sequence[float], states: int = 0,
                         stiffness: float | None = None) -> None:
        if stiffness is None:
            stiffness = needed_stiffness(law, params, states)
        masses = storey_masses(self.specimen)
        for s, m in zip(self.storeys, masses, strict=True):
            self.add_force(law, s, None, params, states, m, stiffness)

    def add_storey_quadratic_damper(self, c2: float) -> None:
        for s in self.storeys:
            self.quadratic.append((s, c2))

    def add_output_filter(self, fn: Callable, channels=None) -> None:
        self.filters.append((fn, None if channels is None else frozenset(channels)))

    # -- the matrices ------------------------------------------------------------------
    def matrices(self):
        M0, K0, C0, names = self._full
        coords = [c for c in self.active if c not in self.extra]
        keep = [names.index(c) for c in coords]
        n0, n = len(keep), len(self.active)
        order = coords + list(self.extra)
        M, K, C = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
        rows, cols = np.ix_(keep, keep)
        for X, X0 in ((M, M0), (K, K0), (C, C0)):
            X[:n0, :n0] = X0[rows, cols]
        for k, mass in enumerate(self.extra.values()):
            M[n0 + k, n0 + k] = mass
        ix = {c: i for i, c in enumerate(order)}
        for a, b, k, c in self.springs:
            for X, v in ((K, k), (C, c)):
                i = ix[a]
                X[i, i] += v
                if b is not None:
                    j = ix[b]
                    X[j, j] += v
                    X[i, j] -= v
                    X[j, i] -= v
        return order, ix, M, K, C


def switchable(law) -> tuple[Stage, ...]:
    """The catalog's stages (`registry.stock_stages`) a nonlinear reduced model's element
    carries behind flags, its law's own switched on: all but one that would clash with a
    stage of the law's own (another of the same name; a second control or feedback
    stage)."""
    own = [s for s, _ in law.stages]
    stock = stock_stages()
    fixed = [s for s in own if not any(s is t for t in stock)]
    names = {s.name for s in fixed}
    single = {s.kind for s in fixed} & {"control", "feedback"}
    return tuple(s for s in stock if s.name not in names and s.kind not in single)


class ReducedModel(ModalOutputs):
    """Predicts a run's channels from its command for a given `Physics`."""

    def __init__(self, physics: phys.Physics, vt: VirtualTable | None = None, *,
                 kernels: bool = True) -> None:
        """`kernels=False`: the model's structure only (its matrices, its stages checked,
        `linear`), no element generated, compiled or loaded: whether `physics` can be built
        on `vt` and whether it is linear (a diagnosis asks that of every candidate, most of
        which it never simulates in this process). It cannot simulate."""
        m = ReducedAssembly(physics, vt or virtual_table())
        self.physics, self.vt = physics, m.vt
        physics.apply(m, "reduced")
        self.assembly = m
        order, ix, M, K, C = m.matrices()
        self.coords, self.ix = order, ix
        n = len(order)
        na = len(m.loops)
        Aw, Wq, Wv, Fw = np.zeros((na, na)), np.zeros((na, n)), np.zeros((na, n)), \
            np.zeros((n, na))
        for k, (c, a, b_q, b_v, f) in enumerate(m.loops):
            Aw[k, k], Wq[k, ix[c]], Wv[k, ix[c]], Fw[ix[c], k] = a, b_q, b_v, f
        c2 = np.zeros(n)
        for c, v in m.quadratic:
            c2[ix[c]] += v
        ax = np.zeros(n)
        ax[ix[m.moving]] = 1.0
        if m.reaction is not None:
            ax[ix[m.reaction]] = -1.0
        self.M, self.K, self.C, self.c2, self.ax, self.bF = M, K, C, c2, ax, ax.copy()
        self.Aw, self.Wq, self.Wv, self.Fw = Aw, Wq, Wv, Fw
        self.Minv = np.linalg.inv(M)
        law = lumped_law(self.vt, m.servo, m.stages)
        self.T, self.Tp, self.g, self.kp, self.kv = law.kernel()
        if self.T.shape != (1, 1):  # the kernel steps one lumped actuator on one DOF
            raise RuntimeError(f"the reduced model's actuator law is {self.T.shape}, not 1 x 1")
        self.storeys, self.h_top, self.specimen = m.storeys, m.h_top, m.specimen
        self.max_step = m.max_step
        self._law = law
        #: its nonlinear parts: force elements, quadratic dampers, nonlinear stages of the
        #: servo law (an effect that adds none is linear, whatever model it joins)
        self.nonlinear_parts = len(m.elements) + int(np.count_nonzero(c2)) + \
            sum(not s.linear for s, _ in law.stages)
        #: a linear model is stepped exactly (`reduced_kernel.simulate_linear`)
        self.linear = (not m.elements and not np.any(c2) and law.linear and LINEAR_PATH)
        if kernels:
            self._element(m.elements)  # the stage set's compiled element (`element`, `sp`)
        else:  # structure only: its stages checked, no element
            law.check()
            self.element = self.elem = self.sp = None
        if self.linear and kernels:
            self._linear = linear_system(self.element.module, n, self.Minv, K, C, c2, self.bF,
                                         ax, self.sp, self.T, self.Tp, self.g, self.kp,
                                         self.kv, Aw, Wq, Wv, Fw)
            self._holds: dict[float, tuple] = {}

    def _hold(self, h: float):
        if h not in self._holds:
            self._holds[h] = first_order_hold(self._linear[0], self._linear[1], h)
        return self._holds[h]

    def _element(self, elements: list[ForceElement]) -> None:
        """The stage set's compiled element (`element`), with the force elements' laws
        written into it (`compose.ElementLaw`: cached on disk like the stages, one module
        for every coordinate they act on), their parameters `pe` and coordinates `ia`,
        `ib`; a law numba cannot compile runs as Python instead (slower, said)."""
        law = self._law
        self.python = False
        self.ne, self.pe = sum(e.states for e in elements), np.zeros(0)
        self.elem = None
        # stepped by RK4, the catalog's stages ride along switched off: one integrator for
        # every set of them (`compose`); a linear model's element is its own (its states)
        stock = () if self.linear else switchable(law)
        if not elements:
            self.element = law.composition(KERNELS, switchable=stock)
            self.sp = law.vector(self.element)
            return
        self.pe = np.concatenate([e.params for e in elements])
        self.ia = np.array([self.ix[e.a] for e in elements], dtype=np.int64)
        self.ib = np.array([-1 if e.b is None else self.ix[e.b] for e in elements],
                           dtype=np.int64)
        laws = tuple(ElementLaw(e.law, e.states, len(e.params), e.names) for e in elements)
        try:  # compile now: a law numba cannot type runs as Python instead (slower)
            self.element = law.composition(KERNELS, elements=laws, switchable=stock)
            n = len(self.ix)
            self.element.module.elements(np.zeros(n), np.zeros(n), np.zeros(self.ne), self.pe,
                                         np.zeros(n), np.zeros(self.ne), self.ia, self.ib)
            self.elem = self.element.module.elements
        except Exception as e:  # numba's typing errors have many classes
            if interrupted(e):  # Ctrl-C while numba compiled: not a law it cannot type
                raise KeyboardInterrupt from e
            self.element = law.composition(KERNELS, switchable=stock)
            self.elem, _, self.pe = python_elements(elements, self.ix)
            self.python = True
            names = ", ".join(sorted({law_where(e.law) for e in elements}))
            why = (str(e).strip().splitlines() or [""])[0][:160]
            warnings.warn(f"a force law numba cannot compile runs as Python (slower): "
                          f"{names}: {type(e).__name__}: {why}", RuntimeWarning, stacklevel=3)
        self.sp = law.vector(self.element)

    def _measured_force(self, F: np.ndarray, P: np.ndarray) -> np.ndarray:
        """The lumped actuator's force as the run's force channels measure it
        (`vt.force_measured`): "load_cell", the force F the rod transmits to the platen
        (A P_L after the force stages, e.g. less friction); "delta_p", A P_L (eq 6.3)."""
        if self.vt.force_measured == "delta_p":
            return self.sp[PISTON_AREA] * P
        return F

    def histories(self, t: np.ndarray, x_c: np.ndarray) -> Histories:
        """The integrator's histories (`Histories`) on the model step h = dt/up of the
        command x_c on the uniform grid `t`. The model integrates at the run step divided
        by the smallest integer that brings it to `SIM_DT` (or a stiff element's step) or
        below (any sample rate); the command is interpolated band-limited
        (`resample_poly`) in between."""
        if self.element is None:
            raise RuntimeError("a structure-only reduced model (kernels=False) cannot simulate")
        t = np.asarray(t, dtype=float)
        if len(t) < 2:
            raise VtableError("the model needs a command of at least two samples")
        dt = float((t[-1] - t[0]) / (len(t) - 1))
        if not dt > 0:
            raise VtableError(f"run step {dt:g} s: the time column must increase")
        up = max(1, math.ceil(dt / self.max_step - 1e-9))
        h = dt / up
        xc = upsampled(x_c, len(t), up)
        nq = self.M.shape[0]
        args = (xc, h, nq, *self.integrated)
        if self.linear:
            Phi, G0, G1 = self._hold(h)
            with first_compile(simulate_linear):
                Q, Qd, Qdd, F, PL = simulate_linear(xc, nq, *self._linear, Phi, G0, G1)
        elif self.python:
            Q, Qd, Qdd, F, PL = simulate_reduced_python(self.element.module, *args, self.elem,
                                                        self.ne, self.pe)
        else:
            Q, Qd, Qdd, F, PL = self._integrated(args)
        return Histories(h, up, xc, Q, Qd, Qdd, F, PL)

    @property
    def integrated(self) -> tuple[np.ndarray, ...]:
        """The arrays the compiled integrator reads after the command, its step and the
        coordinates' count, in its argument order: M⁻¹, K, C, c₂, b_F, the actuator's
        direction, the stage values `sp`, the lumped law's T, T⁺, g, k_p, k_v, and the
        auxiliary loops' Aw, Wq, Wv, Fw (`reduced_kernel.simulate_reduced`). What is kept
        by the model's dynamics (`reduced_parts.kept_histories`, the unrolled kernel's
        constants) is kept by these."""
        return (self.Minv, self.K, self.C, self.c2, self.bF, self.ax, self.sp, self.T,
                self.Tp, self.g, self.kp, self.kv, self.Aw, self.Wq, self.Wv, self.Fw)

    def _integrated(self, args: tuple):
        """The compiled integrator on `args`: the loop unrolled for the model's shape
        (`reduced_unrolled`) when it has one, else `reduced_kernel.simulate_reduced` (with
        the force elements when there are); a law that needs numba's reference counting (it
        allocates) gets the element compiled with it (`compose.counted`) and the same call
        again. Ctrl-C while numba compiles is an interrupt, not such a law."""
        steps = unrolled.kernel(self)  # its mechanics unrolled for its shape (the same
        if steps is not None:  # histories, faster: `reduced_unrolled`)
            try:
                return unrolled.simulate(steps, self, args[0], args[1])
            except numba.core.errors.NumbaError as e:
                if interrupted(e):
                    raise KeyboardInterrupt from e
                unrolled.refuse(self)  # the generic loop, below, from now on
        module = self.element.module
        try:
            if self.elem is None:
                return simulate_reduced(module, *args)
            return simulate_reduced(module, *args, self.pe, self.ia, self.ib, self.ne)
        except numba.core.errors.NumbaError as e:
            if interrupted(e):
                raise KeyboardInterrupt from e
            again = counted(self.element)
            if again is self.element:  # counted already: the law's own error
                raise
            self.element = again
            if self.elem is not None:
                self.elem = again.module.elements
            return self._integrated(args)

    def simulate(self, t: np.ndarray, x_c: np.ndarray) -> Channels:
        """The run's channels (`Channels`, SI) on the uniform time grid `t` of a command x_c
        sampled on it (the integration: `histories`)."""
        h, up, _xc, Q, Qd, Qdd, F, PL = self.histories(t, x_c)
        out = filtered(self.assembly.filters, self._channels(Q, Qd, Qdd, F, PL), 1.0 / h)
        return Channels(self._aliased({k: v[::up] for k, v in out.items()}),
                        np.asarray(t, dtype=float), h)

    def _aliased(self, out: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The channels each lumped quantity stands for: every horizontal actuator's
        displacement and force, the second top-mass accelerometer and potentiometer."""
        force = out.pop("h1_force")
        for a in self.vt.group("horizontal"):  # the lumped actuator stands for each
            out[f"{a.name.lower()}_disp"] = out["avg_hdisp"]
            out[f"{a.name.lower()}_force"] = force
        if "acc_n_ne" in out:
            out["acc_n_nw"] = out["acc_n_ne"]
            out["pot_n_se"] = out["pot_n_sw"]
        return out

    def _channels(self, Q, Qd, Qdd, F, PL) -> dict[str, np.ndarray]:
        """The lumped model's channels from its histories (linear in them), before the
        output filters and the aliases (`_aliased`). A model that blew up (a fit's trial
        point) has infinities in its histories before its NaN (`reduced_kernel._blown`):
        its channels are NaN there, without numpy's warning (a fit reads them as the
        failed point they are; the warning reached a user's terminal with this file's
        line)."""
        with np.errstate(invalid="ignore", over="ignore"):
            ix = self.ix
            n = len(F)
            x = ix["x"]
            slides = [ix[s] for s in self.storeys]
            drift = Q[:, slides].sum(axis=1) if slides else np.zeros(n)
            drift_a = Qdd[:, slides].sum(axis=1) if slides else np.zeros(n)
            ip = ix.get("pitch")
            th = Q[:, ip] if ip is not None else np.zeros(n)
            th_a = Qdd[:, ip] if ip is not None else np.zeros(n)
            na = self.assembly.n_actuators
            out = {"avg_hdisp": Q @ self.ax, "h_vel": Qd @ self.ax, "avg_hacc": Qdd[:, x],
                   "pitch_disp": th, "pitch_acc": th_a,
                   "h1_force": self._measured_force(F, PL) / na}
            if slides:
                out["acc_n_ne"] = Qdd[:, x] + self.h_top * th_a + drift_a
                out["pot_n_sw"] = Q[:, x] + self.h_top * th + drift
            # every floor K (an SDOF frame's floor 1 is its top mass): the slides chain
            # (`tables.bodies.specimen_bodies`), so floor K moves by x + h_K θ + Σ_{i≤K} x_s,i
            for k, h_k in enumerate(self.assembly.h_floors, 1):
                below = slides[:k]
                if k == len(slides):  # the top floor is the top-mass instruments' quantity
                    out[f"floor{k}_acc"], out[f"floor{k}_disp"] = out["acc_n_ne"], out["pot_n_sw"]
                    continue
                out[f"floor{k}_acc"] = Qdd[:, x] + h_k * th_a + Qdd[:, below].sum(axis=1)
                out[f"floor{k}_disp"] = Q[:, x] + h_k * th + Q[:, below].sum(axis=1)
            if slides:
                floors = [out[f"floor{k}_acc"] for k in range(1, len(slides) + 1)]
                out.update(storey_channels([Q[:, i] for i in slides], floors,
                                           storey_masses(self.specimen)))
            return out

    def predict(self, run: Run) -> Channels:
        """The run's predictable channels, from its command (h_span)."""
        return self.simulate(run.time, run.channel("h_span"))
