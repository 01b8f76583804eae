"""The multibody virtual table realising a `Physics`, composed from the same vocabulary
as the reduced model (`vtable.effects.base.Assembly`).

`VirtualAssembly` starts from the chapter-7 base: the virtual table's MjSpec
(`mjcf.table_spec`) with the pitch joint removed, the horizontal loop from the base's open
loop (no RC filter) and the passive stabilizers; effects then edit the spec
(`vtable.mjcf.edit`: free a joint, a reaction mass, pistons between actuators and platen,
storey actuators), set the hydraulic element's options, add force-law controllers and
output filters. `finalize` compiles and picks the controllers: the linear, fused
`ServoController` while every stage of the horizontal loop is linear, the compiled
`HydraulicServo` (the stage set's element) once one is not.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace

from vtable.controllers import (
    ForceLawController,
    HydraulicServo,
    PassiveStabilizers,
    ServoController,
    quadratic_damper,
)
from vtable.effects.table import TableView
from vtable.hydraulics.law import group_law
from vtable.hydraulics.stage import Stage, add_stage
from vtable.hydraulics.table_stages import table_stages
from vtable.mjcf import edit
from vtable.mjcf.builder import BuiltModel, compile_table, table_spec
from vtable.models import physics as phys
from vtable.models.stiffness import needed_stiffness
from vtable.opensees.controller import OpenSeesController
from vtable.opensees.model import load_model
from vtable.params.virtual import VirtualTable
from vtable.tables.eerc import with_rocking

MAX_STEP = 1e-3  # s: the virtual table's largest MuJoCo/control step


class VirtualAssembly:
    """The virtual table under construction (see the module docstring)."""

    def __init__(self, ph: phys.Physics, vt: VirtualTable, timestep: float = MAX_STEP) -> None:
        vt = ph.on_table(vt)
        base = phys.base_hydraulics(ph, vt)
        servo = replace(vt.horizontal_servo, k_t=base.k_t, k_p=base.k_p, k_ct=base.k_ct,
                        volume=base.volume, area=base.area, beta=base.beta, k_v=base.k_v)
        self.vt = replace(vt, horizontal_servo=servo)
        self.specimen = ph.specimen
        self.ts = table_spec(self.vt, ph.specimen, timestep=timestep, with_meshes=False)
        edit.lock_joint(self.ts, "pitch")
        self.servo = base
        self.stages: list[tuple[Stage, dict[str, float]]] = []
        self.table = TableView.of(self.vt, piston_area=base.area)
        self.controllers: list = []
        self.structures: list[tuple[str, float, float, float]] = []
        #: (fn(x, fs), the channels it applies to or None: all)
        self.filters: list[tuple[Callable, frozenset | None]] = []
        self.n_actuators = len(self.vt.group("horizontal"))
        self.max_step = MAX_STEP
        for stage, params in table_stages(vt, rc=False):  # its valve lag, its
            self.add_stage(stage, **params)                # controller's terms
        if vt.control is not None:  # a digital controller's own terms (ω·dt ≤ 1)
            rate = group_law(vt, "horizontal", stages=[vt.control.use]).fastest_rate()
            self.max_step = min(self.max_step, 1.0 / rate)

    def _stiff(self, mass: float, stiffness: float) -> None:
        """MuJoCo's semi-implicit Euler with an explicit controller force is stable to
        ω·dt ≈ 2: keep ω·dt ≤ 1 (accuracy: five steps a period)."""
        if stiffness > 0 and mass > 0:
            self.max_step = min(self.max_step, 1.0 / math.sqrt(stiffness / mass))

    # -- the vocabulary ----------------------------------------------------------------
    def add_stage(self, stage: Stage, **params: float) -> None:
        add_stage(self.stages, stage, params)

    def unlock(self, dof: str) -> None:
        phys.check_dof(self.vt, dof)
        edit.unlock_joint(self.ts, dof)

    def set_rocking(self, k_theta: float, c_theta: float) -> None:
        self.vt = with_rocking(self.vt, k_theta, c_theta)

    def add_reaction_mass(self, name: str, mass: float, stiffness: float,
                          damping: float) -> None:
        edit.add_reaction_mass(self.ts, name, mass, stiffness, damping)

    def add_dof(self, name: str, mass: float) -> None:
        edit.add_slide_body(self.ts, name, mass)

    def add_spring(self, a: str, b: str | None, stiffness: float, damping: float) -> None:
        edit.add_spring(self.ts, a, b, stiffness, damping)

    def add_structure(self, name: str, mass: float, stiffness: float, damping: float) -> None:
        self.add_dof(name, mass)
        self.add_spring(name, "x", stiffness, damping)
        self.structures.append((name, float(mass), float(stiffness), float(damping)))

    def set_actuator(self, moving: str | None = None, reaction: str | None = None) -> None:
        edit.set_actuator(self.ts, moving, reaction)

    def add_force(self, law: Callable, a: str, b: str | None = None,
                  params: Sequence[float] = (), states: int = 0, mass: float = 0.0,
                  stiffness: float | None = None) -> None:
        """A force-law controller on a tendon of length q_a - q_b."""
        if stiffness is None:
            stiffness = needed_stiffness(law, params, states)
        self._stiff(mass, stiffness)
        t = edit.relative_tendon(self.ts, f"force_{a}_{b or 'ground'}_{len(self.controllers)}",
                                 a, b)
        self.ts.force_actuators.append(t)
        self.controllers.append(ForceLawController((t,), law, params, states))

    def insert_at_actuators(self, name: str, mass: float, law: Callable,
                            params: Sequence[float], states: int = 0,
                            stiffness: float | None = None) -> None:
        if stiffness is None:
            stiffness = needed_stiffness(law, params, states)
        self._stiff(mass, stiffness)
        acts = edit.insert_at_actuators(self.ts, name, mass)
        # each actuator carries its share of the lumped connection's force
        self.controllers.append(ForceLawController(tuple(acts), law, params, states,
                                                   scale=1.0 / len(acts)))

    def add_storey_force(self, law: Callable, params: Sequence[float], states: int = 0,
                         stiffness: float | None = None) -> None:
        if stiffness is None:
            stiffness = needed_stiffness(law, params, states)
        for m in self.ts.structure_masses:
            self._stiff(m, stiffness)
        acts = edit.add_storey_actuators(self.ts)
        self.controllers.append(ForceLawController(tuple(acts), law, params, states))

    def add_storey_quadratic_damper(self, c2: float) -> None:
        self.add_storey_force(quadratic_damper, [c2])

    def add_opensees(self, spec) -> None:
        """An OpenSees specimen stepped with the platen (`opensees.controller`)."""
        depth = self.vt.table.geometry.actuator_line_depth
        self.controllers.append(OpenSeesController(load_model(spec.model), depth,
                                                 float(self.ts.spec.option.timestep)))

    def add_output_filter(self, fn: Callable, channels=None) -> None:
        self.filters.append((fn, None if channels is None else frozenset(channels)))

    # -- the model ---------------------------------------------------------------------
    def finalize(self) -> tuple[BuiltModel, list]:
        """Compile the spec and return it with its controllers."""
        built = compile_table(self.ts)
        vt = self.vt
        law = group_law(vt, "horizontal", self.servo, stages=self.stages)
        if law.linear:
            ctl = [ServoController(vt, laws={"horizontal": law})]
        else:
            ctl = [HydraulicServo(vt, law=law),
                   ServoController(vt, groups=("vertical",))]
        if vt.stabilizers.pairs:
            ctl.append(PassiveStabilizers(vt))
        built.vt = vt
        return built, ctl + self.controllers

