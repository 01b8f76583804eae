"""The multibody virtual table's description (SI): the platen's hardware (`TableHardware`),
the layout assumptions, the actuators and stabilizers, the servo constants and control
settings — one object the MJCF builder, the controllers and the analytic and reduced
models read. Plain data: the tables vtable models are built from the presets with the
report's formulas in `vtable.tables`."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from vtable.errors import VtableError
from vtable.params.base import Params, plain, quantity
from vtable.params.loops import OpenLoop
from vtable.params.table import (
    DirectionSettings,
    ServoConstants,
    TableHardware,
)
from vtable.units import G

#: the source of the limits a description of a preset's table changed (`limits_source`)
DECLARED = "declared"


@dataclass(frozen=True)
class MultibodyLayout(Params):
    """Layout assumptions of the multibody table (eerc.toml [multibody])."""

    rib_width: float = quantity("in", "rib_width_in", minimum=0, exclusive=False)
    rib_depth: float = quantity("in", "rib_depth_in", minimum=0, exclusive=False)
    rib_offset: float = quantity("in", "rib_offset_in", minimum=0, exclusive=False)
    horizontal_length: float = quantity("in", "horizontal_length_in", minimum=0)
    vertical_length: float = quantity("in", "vertical_length_in", minimum=0, exclusive=False)
    stabilizer_length: float = quantity("in", "stabilizer_length_in", minimum=0, exclusive=False)
    stabilizer_beta: float = quantity("psi", "stabilizer_beta_psi", minimum=0)
    vertical_k_ct: float = quantity("in3/s/psi", "vertical_k_ct_in3_per_s_per_psi", minimum=0,
                                    exclusive=False)
    pitch_loop_f: float = quantity("Hz", "pitch_loop_f_hz", minimum=0, exclusive=False)
    twist_gain_factor: float = plain()
    twist_delta_p_factor: float = plain()
    roll_delta_p_factor: float = plain()
    source: str = plain(default="")


@dataclass(frozen=True)
class Actuator:
    """One actuator or stabilizer: attachment on the slab and on the foundation (SI,
    world frame at rest, origin at the table-top centre), and its DOF participation."""

    name: str
    kind: str  # "horizontal" | "vertical" | "stabilizer"
    slab_point: tuple[float, float, float]
    foundation_point: tuple[float, float, float]
    area: float
    stroke: float | None  # m, total (None: not declared)
    capacity: float
    flow: float | None

    @property
    def axis(self) -> np.ndarray:
        d = np.subtract(self.slab_point, self.foundation_point)
        return d / np.linalg.norm(d)


@dataclass(frozen=True)
class Stabilizers:
    """Cross-connected passive stabilizers (§8.3): per-piston stiffness and damping acting
    on the antisymmetric motion of each pair only."""

    pairs: tuple[tuple[str, str], ...]
    stiffness: float  # F/Δx per piston, N/m (eq 8.3, oil term)
    damping: float  # N s/m per piston
    volume: float  # oil volume per side, m³
    beta: float


@dataclass(frozen=True)
class VirtualTable:
    """A shaking table as every model reads it (the multibody table, its controllers, the
    reduced and analytic models, identification): built once by `vtable.tables` — the EERC
    table from its preset (`virtual_table()`), a lab's declared table or a uniaxial platen
    (`described_table`, what `vtable.runs.lab.lab_table` makes of a run's [table])."""

    table: TableHardware
    layout: MultibodyLayout
    actuators: tuple[Actuator, ...]
    horizontal_servo: ServoConstants  # Table B.5, per horizontal actuator
    vertical_servo: ServoConstants | None  # derived (module docstring), per vertical actuator
    pitch_loop: OpenLoop | None  # §8.6.2 target of the vertical calibration
    stabilizers: Stabilizers
    settings: dict[str, DirectionSettings]
    dofs: tuple[str, ...] = ("x", "z", "roll", "pitch", "twist")  # the platen's DOFs
    knobs: bool = True  # the Table 3.2 knobs scale the gains (False: physical gains, a PID)
    valve_lag: float = 0.0  # s: the horizontal servovalves' time constant
    #: the horizontal controller's control stage and its parameters (a digital
    #: controller's terms beyond eqs 6.1-6.4: `vtable.controllers.kinds`); None: none
    control: tuple | None = None
    #: the horizontal controller's kind (`vtable.controllers.kinds`): the EERC table's
    #: three-variable controller, a lab's PID, ...
    controller: str = "three_variable"
    name: str = "eerc"
    com_height: float | None = None  # m: platen c.o.m. above the actuator line (None: shape's)
    #: what the horizontal force channels measure: "load_cell", the net force the rod
    #: transmits to the platen (after friction and any force stage); "delta_p", A·ΔP
    force_measured: str = "load_cell"
    #: the run-format [table] the table was declared with (a run made on it writes this
    #: back); None: a preset, written as its name
    declared: dict | None = field(default=None, compare=False)

    # -- what a lab declares of its table, read from the one description -----------------
    @property
    def platen_mass(self) -> float:
        """kg: the platen's mass."""
        return self.table.geometry.mass

    @property
    def pitch_inertia(self) -> float:
        """kg m²: the platen's pitch inertia about the horizontal actuator line."""
        return self.table.geometry.pitch_inertia

    @property
    def n_actuators(self) -> int:
        """The horizontal actuators (lumped by the reduced model)."""
        return len(self.group("horizontal"))

    @property
    def uniaxial(self) -> bool:
        return tuple(self.dofs) == ("x",)

    @property
    def pitches(self) -> bool:
        return "pitch" in self.dofs

    @property
    def stroke(self) -> float | None:
        """m (± amplitude) of the horizontal actuators; None: not declared."""
        return self.table.specs.stroke_h

    @property
    def velocity(self) -> float | None:
        """m/s: the horizontal velocity limit; None: not declared."""
        return self.table.specs.velocity_h

    @property
    def acceleration(self) -> float | None:
        """m/s²: the horizontal acceleration limit; None: not declared."""
        return self.table.specs.acceleration_h

    @property
    def payload(self) -> float | None:
        """kg: the specimen mass the table carries; None: not declared."""
        w = self.table.specs.weight_capacity
        return None if w is None else w / G

    @property
    def band(self) -> tuple[float, float] | None:
        """Hz: the table's operating band; None: not declared."""
        s = self.table.specs
        return None if s.bandwidth is None else (s.band_low, s.bandwidth)

    @property
    def limits_source(self) -> str:
        """Where the table's limits come from (for messages)."""
        if self.name == "eerc" and self.table.specs.source != DECLARED:
            return "Table 2.2"
        return f"the {self.name} table's declared limits" if self.name == "eerc" else \
            f"the {self.name} table's limits"

    @property
    def pivot_depth(self) -> float:
        """Depth of the horizontal actuator line below the table top (m), §4.2.1."""
        return self.table.geometry.actuator_line_depth

    def actuator(self, name: str) -> Actuator:
        for a in self.actuators:
            if a.name == name:
                return a
        raise VtableError(f"no actuator {name!r}")

    def group(self, kind: str) -> tuple[Actuator, ...]:
        return tuple(a for a in self.actuators if a.kind == kind)

    def with_settings(self, **dirs: DirectionSettings) -> VirtualTable:
        unknown = set(dirs) - set(self.settings)
        if unknown:
            raise VtableError(f"unknown control direction {sorted(unknown)[0]!r}")
        return replace(self, settings={**self.settings, **dirs})

    def gain_scales(self, direction: str) -> tuple[float, float, float]:
        """(gain, ΔP, rate) multipliers of a DOF relative to the calibrated reference, from
        the knob factors (Tables B.1-B.4 plus the [multibody] assumptions); 1 for a table
        whose gains are physical (a PID)."""
        if not self.knobs:
            return 1.0, 1.0, 1.0
        s = self.settings[direction]
        kf = self.table.knob_factors
        lay = self.layout
        if direction == "horizontal":
            ref = self.table.standard.horizontal
            return tuple(_ratio(kf.factor("horizontal", k, getattr(s, k)),
                                kf.factor("horizontal", k, getattr(ref, k)))
                         for k in ("gain", "delta_p", "rate"))  # type: ignore[return-value]
        if direction == "twist":
            g_ref = kf.factor("horizontal", "gain", self.table.standard.horizontal.gain)
            p_ref = kf.factor("horizontal", "delta_p", self.table.standard.horizontal.delta_p)
            std = self.table.standard.twist
            g = lay.twist_gain_factor * (s.gain / std.gain if std.gain else 1.0)
            p = lay.twist_delta_p_factor * (s.delta_p / std.delta_p if std.delta_p else 1.0)
            return g / g_ref, p / p_ref, 0.0
        # vertical group: anchored at the pitch standard setting (the calibration)
        ref = self.table.standard.pitch
        g_ref = kf.factor("pitch", "gain", ref.gain)
        p_ref = kf.factor("pitch", "delta_p", ref.delta_p)
        g = kf.factor(direction, "gain", s.gain)
        if direction == "roll":
            p = lay.roll_delta_p_factor * (s.delta_p / 2.0)
        else:
            p = kf.factor(direction, "delta_p", s.delta_p)
        return g / g_ref, p / p_ref, 0.0


def _ratio(a: float, b: float) -> float:
    return a / b if b else 0.0


