"""`Physics`: what a model of the table contains — the base (horizontal servo loop as
open-loop parameters on the bare table, the specimen) and the effects with their
parameters. The reduced model and the virtual table both read it, and every effect
parameter becomes SI here, once."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from vtable import units
from vtable.analytic.servo import open_loop_from_servo, servo_from_open_loop
from vtable.effects.catalog import CATALOG, effect
from vtable.effects.kernel import (
    AIR,
    BETA,
    FR,
    KCT,
    KP,
    KT,
    KV,
    N_SERVO,
    PMEAN,
    PS,
    QMAX,
    RC,
    TAU,
    VEPS,
    A,
    V,
)
from vtable.params.loops import OpenLoop
from vtable.params.specimen import NoSpecimen, SDOFSpecimen, Specimen
from vtable.params.table import ServoConstants
from vtable.params.virtual import VirtualTable, virtual_table

N_HORIZONTAL = 3


@dataclass(frozen=True)
class Physics:
    """Base model plus effects {name: {param: value in report units}}."""

    open_loop: OpenLoop
    specimen: Specimen
    effects: dict[str, dict[str, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        checked = {name: effect(name).check(p, name) for name, p in self.effects.items()}
        object.__setattr__(self, "effects", checked)

    def has(self, name: str) -> bool:
        return name in self.effects

    def with_effect(self, name: str, params: dict[str, float] | None = None) -> Physics:
        return dataclasses.replace(self, effects={**self.effects, name: dict(params or {})})

    def without(self, name: str) -> Physics:
        return dataclasses.replace(self, effects={k: v for k, v in self.effects.items()
                                                  if k != name})

    def si(self, name: str, param: str) -> float:
        """An effect parameter in SI."""
        p = next(x for x in CATALOG[name].params if x.name == param)
        v = self.effects[name][param]
        if p.unit == "1/in":  # a rate per inch of drift
            return v / units.to_si(1.0, "in")
        return units.to_si(v, p.unit) if p.unit in units.UNITS else v

    @property
    def label(self) -> str:
        return " + ".join(["base", *self.effects])


def nominal_open_loop(vt: VirtualTable | None = None) -> OpenLoop:
    """The bare-table loop implied by Table B.5 (eq 6.16 with the table mass m_t/3 per
    actuator): the starting point for the base parameters."""
    vt = vt or virtual_table()
    return open_loop_from_servo(per_actuator_template(vt))


def per_actuator_template(vt: VirtualTable) -> ServoConstants:
    return dataclasses.replace(vt.horizontal_servo, mass=vt.table.geometry.mass / N_HORIZONTAL)


def servo_constants(ph: Physics, vt: VirtualTable) -> ServoConstants:
    """Per-actuator physical constants for the base loop (eq 6.16 inverted)."""
    return servo_from_open_loop(ph.open_loop, per_actuator_template(vt))


def servo_vector(ph: Physics, vt: VirtualTable, n_equivalent: int = 1) -> np.ndarray:
    """The kernel's parameter vector for `n_equivalent` actuators lumped into one (1 for
    each real actuator; 3 for the reduced model's equivalent actuator)."""
    c = servo_constants(ph, vt)
    s = np.zeros(N_SERVO)
    k = n_equivalent
    s[A], s[V], s[BETA] = c.area * k, c.volume * k, c.beta
    s[KT], s[KCT], s[KP], s[KV] = c.k_t * k, c.k_ct * k, c.k_p, c.k_v
    s[PMEAN] = vt.table.geometry.supply_pressure
    s[VEPS] = 1e-3
    if ph.has("force_feedback_filter"):
        s[RC] = ph.si("force_feedback_filter", "rc")
    if ph.has("valve_flow_nonlinearity"):
        s[PS] = ph.si("valve_flow_nonlinearity", "supply_pressure")
        s[PMEAN] = s[PS]
    if ph.has("actuator_friction"):
        s[FR] = ph.si("actuator_friction", "friction") * k / N_HORIZONTAL
    if ph.has("flow_saturation"):
        s[QMAX] = ph.si("flow_saturation", "v_max") * c.area * k
    if ph.has("valve_dynamics"):
        s[TAU] = ph.si("valve_dynamics", "tau")
    if ph.has("oil_column_air"):
        s[AIR] = ph.effects["oil_column_air"]["air_ratio"]
    return s


def rocking_spring(ph: Physics) -> tuple[float, float]:
    return ph.si("pitch_flexibility", "k_theta"), ph.si("pitch_flexibility", "c_theta")


def foundation(ph: Physics, vt: VirtualTable) -> tuple[float, float, float]:
    """Reaction-block mass (§2.2), spring and dashpot of foundation_compliance."""
    m = vt.table.geometry.foundation_weight / units.G
    w = 2 * math.pi * ph.si("foundation_compliance", "f_f")
    xi = ph.effects["foundation_compliance"]["xi_f"]
    return m, m * w * w, 2 * xi * w * m


def quadratic_damping(ph: Physics, spec: Specimen) -> float:
    """c₂ of amplitude_dependent_damping: ξ_eq = ξ + γ·a for a quadratic damper needs
    c₂ = 3π m γ/4 (equivalent viscous c = 8 c₂ ω a/(3π) at amplitude a)."""
    if not ph.has("amplitude_dependent_damping") or isinstance(spec, NoSpecimen):
        return 0.0
    gamma = ph.si("amplitude_dependent_damping", "gamma")
    m = spec.mass if isinstance(spec, SDOFSpecimen) else spec.masses[-1]
    return 3 * math.pi * m * gamma / 4
