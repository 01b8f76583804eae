"""The EERC shaking table: geometry (§2.2), actuators (Table 2.1), specifications
(Table 2.2), servo constants (Table B.5) and control knobs (Table 3.2, Tables B.1-B.4).

Values live in ``data/eerc.toml``; these classes give them types, units and checks.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Self

from vtable.errors import VtableError, did_you_mean
from vtable.params.base import Params, check_number, plain, quantity
from vtable.units import G

#: the names `vtable.params` gives (the package's public ones)
__all__ = [
    "ActuatorSpec",
    "ControlSettings",
    "DirectionSettings",
    "KnobFactors",
    "ServoConstants",
    "TableGeometry",
    "TableHardware",
    "TableSpecs"
]

DIRECTIONS = ("horizontal", "pitch", "vertical", "roll", "twist")
KNOBS = ("gain", "delta_p", "rate")


@dataclass(frozen=True)
class TableGeometry(Params):
    """The slab and where things attach to it (§2.2, §4.2.1, run-format positions)."""

    plan_width: float = quantity("ft", "plan_width_ft", minimum=0, source="§2.2")
    thickness: float = quantity("ft", "thickness_ft", minimum=0, source="§2.2")
    #: kg: the platen's mass (a preset gives its weight, `weight_kip`: §2.2, Table 8.1's
    #: 100 kips; a lab's table its mass, kept as declared)
    mass: float = quantity("kg", "mass_kg", minimum=0, source="§2.2, Table 8.1: weight / g")
    pitch_inertia: float = quantity("kip-in-s2", "pitch_inertia_kip_in_s2", minimum=0,
                                    source="Table 8.1")
    actuator_line_depth: float = quantity("in", "actuator_line_depth_in", minimum=0,
                                          source="§4.2.1: 219 - 189.3 in")
    vertical_square: float = quantity("ft", "vertical_square_ft", minimum=0, exclusive=False,
                                      source="§2.2")
    stabilizer_square: float = quantity("ft", "stabilizer_square_ft", minimum=0, exclusive=False,
                                        source="§2.2")
    horizontal_offset: float = quantity("in", "horizontal_offset_in", minimum=0, exclusive=False,
                                        source="run format: H1/H3 at y = +-96 in")
    pit_pressure: float = quantity("psi", "pit_pressure_psi", minimum=0, exclusive=False,
                                   source="§2.2 (bare table)")
    foundation_weight: float = quantity("kip", "foundation_weight_kip", minimum=0, exclusive=False,
                                        source="§2.2")
    supply_pressure: float = quantity("psi", "supply_pressure_psi", minimum=0, exclusive=False,
                                      source="§2.2")
    source: str = plain(default="")

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str = "") -> TableGeometry:
        """As `Params.from_dict`; the platen given by its weight (`weight_kip`, as the report
        gives it) has the mass that weighs that much (divided by standard gravity)."""
        if isinstance(d, dict) and "weight_kip" in d and "mass_kg" not in d:
            key = f"{where or cls.__name__}.weight_kip"
            w = check_number(d["weight_kip"], key, "kip")
            if not w > 0:
                raise VtableError(f"{key}: expected a weight > 0 kip, got {d['weight_kip']!r}")
            d = {**{k: v for k, v in d.items() if k != "weight_kip"}, "mass_kg": w / G}
        return super().from_dict(d, where)

    @property
    def weight(self) -> float:
        """N: the platen's weight m_t g."""
        return self.mass * G


@dataclass(frozen=True)
class TableSpecs(Params):
    """Performance limits of the EERC table (Table 2.2). A limit a table does not have (a
    lab's uniaxial table that declares no stroke, no overhead clearance) is None: nothing
    is checked against it."""

    weight_capacity: float | None = quantity("kip", "weight_capacity_kip", minimum=0)
    overhead_clearance: float | None = quantity("ft", "overhead_clearance_ft", minimum=0)
    overturning_capacity: float | None = quantity("kip-ft", "overturning_kip_ft", minimum=0,
                                                  exclusive=False)
    stroke_h: float | None = quantity("in", "displacement_h_in", minimum=0)
    stroke_v: float = quantity("in", "displacement_v_in", minimum=0, exclusive=False)
    velocity_h: float | None = quantity("in/s", "velocity_h_in_per_s", minimum=0)
    velocity_v: float = quantity("in/s", "velocity_v_in_per_s", minimum=0, exclusive=False)
    acceleration_h: float | None = quantity("g", "acceleration_h_g", minimum=0)
    acceleration_v: float = quantity("g", "acceleration_v_g", minimum=0, exclusive=False)
    bandwidth: float | None = quantity("Hz", "bandwidth_hz", minimum=0)
    #: Hz: where the band starts (Table 2.2's is 0-50 Hz; a lab may declare another)
    band_low: float = quantity("Hz", "band_low_hz", default=0.0, minimum=0, exclusive=False)
    source: str = plain(default="")


@dataclass(frozen=True)
class ActuatorSpec(Params):
    """One MTS actuator (Table 2.1). Passive stabilizers have no servovalve or flow."""

    name: str = plain()
    model: str = plain()
    area: float = quantity("in2", "area_in2", minimum=0)
    stroke: float | None = quantity("in", "stroke_in", minimum=0,
                                    doc="total stroke (None: not declared)")
    capacity: float = quantity("kip", "capacity_kip", minimum=0)
    servovalve: str | None = plain(default=None)
    flow: float | None = quantity("gpm", "flow_gpm", default=None, minimum=0)


@dataclass(frozen=True)
class ServoConstants(Params):
    """Physical constants of one horizontal actuator loop, fitted on the bare table
    (Table B.5), in the notation of eqs 6.1-6.5 and B.4-B.6.

    `mass` is the table mass per horizontal actuator (100 kips / 3g). The pressure
    feedback gain k_p multiplies ΔP (eq B.6), so the force-feedback gain of eq 6.4 is
    k_f = k_p/A and the flow-force coefficient is k_c = k_ct/A (eq C.19).
    """

    k_p: float = quantity("in/psi", "k_p_in_per_psi", minimum=0, exclusive=False)
    k_t: float = quantity("in2/s", "k_t_in2_per_s", minimum=0)
    k_ct: float = quantity("in3/s/psi", "k_ct_in3_per_s_per_psi", minimum=0, exclusive=False)
    rc: float = quantity("s", "rc_s", minimum=0, exclusive=False,
                         doc="RC of the ΔP feedback filter (eq B.4); 0: no filter")
    mass: float = quantity("lb-s2/in", "mass_lb_s2_per_in", minimum=0)
    beta: float = quantity("psi", "beta_psi", minimum=0)
    area: float = quantity("in2", "area_in2", minimum=0)
    volume: float = quantity("in3", "volume_in3", minimum=0)
    k_v: float = quantity("s", "k_v_s", default=0.0, minimum=0, exclusive=False,
                          source="eq B.6: velocity feedback neglected (k_v = 0)")
    damping: float | None = quantity("lb-s/in", "damping_lb_s_per_in", default=None, minimum=0,
                              exclusive=False, doc="viscous damping c of the mass, per actuator",
                              source="the report's models have none")
    source: str = plain(default="")

    @property
    def k_f(self) -> float:
        """Force-feedback gain k_f = k_p/A (m/N), eq 6.4 vs B.6."""
        return self.k_p / self.area

    @property
    def k_c(self) -> float:
        """Flow-force coefficient k_c = k_ct/A (m³/s/N), eq C.19."""
        return self.k_ct / self.area

    def lumped(self, n: int) -> ServoConstants:
        """`n` identical actuators acting together as one: areas, volumes, flows, leakage,
        mass and damping add; pressures and gains stay."""
        return dataclasses.replace(
            self, area=n * self.area, volume=n * self.volume, k_t=n * self.k_t,
            k_ct=n * self.k_ct, mass=n * self.mass,
            damping=None if self.damping is None else n * self.damping)


@dataclass(frozen=True)
class DirectionSettings(Params):
    """Knob positions of one degree-of-freedom controller (Table 3.2)."""

    gain: float = plain()
    delta_p: float = plain()
    rate: float = plain()


@dataclass(frozen=True)
class ControlSettings(Params):
    """Knob settings of the five DOF controllers (Table 3.2)."""

    horizontal: DirectionSettings = plain()
    pitch: DirectionSettings = plain()
    vertical: DirectionSettings = plain()
    roll: DirectionSettings = plain()
    twist: DirectionSettings = plain()
    source: str = plain(default="")

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str = "") -> Self:
        where = where or "control"
        if not isinstance(d, dict):
            raise VtableError(f"{where}: expected a table")
        d = dict(d)
        for k in DIRECTIONS:
            if k in d:
                d[k] = DirectionSettings.from_dict(d[k], f"{where}.{k}")
        return super().from_dict(d, where)


@dataclass(frozen=True)
class KnobFactors:
    """Knob position -> gain factor, per direction and knob (Tables B.1-B.4)."""

    table: dict[str, dict[str, dict[float, float]]]

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str = "knob_factors") -> KnobFactors:
        out: dict[str, dict[str, dict[float, float]]] = {}
        for direction, knobs in d.items():
            if direction not in DIRECTIONS:
                raise VtableError(f"{where}: unknown direction {direction!r}")
            out[direction] = {}
            for knob, values in knobs.items():
                if knob not in KNOBS:
                    raise VtableError(f"{where}.{direction}: unknown knob {knob!r}")
                try:
                    out[direction][knob] = {float(k): float(v) for k, v in values.items()}
                except ValueError:
                    raise VtableError(f"{where}.{direction}.{knob}: knob positions must be "
                                      "numbers") from None
        return cls(out)

    def factor(self, direction: str, knob: str, position: float) -> float:
        """The tabulated factor; an untabulated position is an error listing the known ones."""
        known = self.table.get(direction, {}).get(knob)
        if not known:
            raise VtableError(f"no knob factor table for {direction} {knob} "
                              "(report Tables B.1-B.4)")
        if float(position) not in known:
            listed = ", ".join(f"{k:g}" for k in sorted(known))
            raise VtableError(f"{direction} {knob}={position:g} is not in Tables B.1-B.4; "
                              f"tabulated positions: {listed}")
        return known[float(position)]


@dataclass(frozen=True)
class TableHardware:
    """A table's hardware: the platen's geometry, its limits, its actuators, one horizontal
    actuator's servo constants and the controller's knob settings and factors — the EERC
    table's from its preset file (Tables 2.1, 2.2, 3.2, B.1-B.5), a lab's uniaxial
    platen's from its declaration (`vtable.tables.lab`). Part of the one table description
    the models read (`vtable.params.virtual.VirtualTable.table`)."""

    geometry: TableGeometry
    specs: TableSpecs
    actuators: tuple[ActuatorSpec, ...]
    servo: ServoConstants
    standard: ControlSettings
    knob_factors: KnobFactors

    def actuator(self, name: str) -> ActuatorSpec:
        for a in self.actuators:
            if a.name == name:
                return a
        raise VtableError(f"no actuator {name!r}; the table has "
                          f"{', '.join(a.name for a in self.actuators)}")

    def rated_velocity(self, kind: str = "horizontal") -> float:
        """The servovalves' rating as the actuators' top speed (m/s): Table 2.2's 25 in/s
        horizontal, 15 in/s vertical. The one source of the rating: the appendix C valve's
        rated flow (`rated_flow`) and the flow_saturation effect's cap both read it.

        Table 2.1's catalogue flow of the valves (`ActuatorSpec.flow`, 170 gpm, i.e.
        25.8 in/s over the 25.4 in² piston) is the valve's nameplate, not the table's
        rating; it is kept as data (and for the per-actuator exceedance check).
        """
        if kind not in ("horizontal", "vertical"):
            raise VtableError(f"no rated velocity for {kind!r} actuators (horizontal or "
                              "vertical)")
        v = self.specs.velocity_h if kind == "horizontal" else self.specs.velocity_v
        if v is None:
            raise VtableError(f"the table declares no velocity limit for its {kind} "
                              "actuators ([table.limits] velocity_m_per_s)")
        return v

    def rated_flow(self, name: str) -> float:
        """Rated flow (m³/s) of actuator `name`'s servovalve, fully open: the rated
        velocity of its group times its piston area, q = A v_max (eq C.14's spool stroke
        limit)."""
        kind = {"H": "horizontal", "V": "vertical"}.get(name[:1])
        if kind is None:
            raise VtableError(f"actuator {name} has no servovalve (H* and V* have)")
        return self.rated_velocity(kind) * self.actuator(name).area

    def horizontal_servo(self, settings: DirectionSettings | None = None) -> ServoConstants:
        """Table B.5 constants re-scaled to other horizontal knob settings.

        Each loop gain is proportional to its knob factor (Table B.1), anchored at the
        standard setting at which Table B.5 was fitted: k_t ∝ gain factor, k_p ∝ ΔP
        factor (B.5's k_p equals the ΔP=1.5 factor, §B.5), k_v ∝ rate factor.
        """
        settings = settings or self.standard.horizontal
        ref = self.standard.horizontal
        kf = self.knob_factors

        def ratio(knob: str) -> float:
            new = kf.factor("horizontal", knob, getattr(settings, knob))
            old = kf.factor("horizontal", knob, getattr(ref, knob))
            if old == 0:
                raise VtableError(f"standard horizontal {knob} has a zero factor; cannot scale")
            return new / old

        s = self.servo
        return dataclasses.replace(s, k_t=s.k_t * ratio("gain"), k_p=s.k_p * ratio("delta_p"),
                                   k_v=s.k_v * ratio("rate"))

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str = "table") -> TableHardware:
        need = ("geometry", "specs", "actuators", "servo", "control", "knob_factors")
        for k in need:
            if k not in d:
                raise VtableError(f"{where}: missing table [{k}]")
        extra = sorted(set(d) - set(need) - {"source", "preset", "multibody", "acquisition"})
        if extra:
            raise VtableError(f"{where}: unknown key {extra[0]!r}"
                              f"{did_you_mean(extra[0], need)}; expected {', '.join(need)}")
        return cls(
            geometry=TableGeometry.from_dict(d["geometry"], f"{where}.geometry"),
            specs=TableSpecs.from_dict(d["specs"], f"{where}.specs"),
            actuators=tuple(ActuatorSpec.from_dict(a, f"{where}.actuators[{i}]")
                            for i, a in enumerate(d["actuators"])),
            servo=ServoConstants.from_dict(d["servo"], f"{where}.servo"),
            standard=ControlSettings.from_dict(d["control"], f"{where}.control"),
            knob_factors=KnobFactors.from_dict(d["knob_factors"], f"{where}.knob_factors"),
        )
