"""Specimens: none, a rigid block (§2.5), a SDOF structure (§2.4), a shear building.

Heights are measured from the horizontal actuator line (29.7 in below the table top,
§4.2.1), as in the run format; `from_table_top` converts.

Damping ratios are fractions of critical (0.02, not 2 %): a ratio above 1 (an
overdamped structure, or a percentage written as a fraction) is refused. A shear
building has at most `MAX_STOREYS` storeys.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from vtable.errors import VtableError
from vtable.params.base import Params, check_number, plain, quantity
from vtable.units import G

KINDS = ("none", "rigid", "sdof", "shear_building")
#: the most storeys a shear building may have (eq 4.5 models; a lab specimen has a few)
MAX_STOREYS = 50
#: structural damping ratios are fractions of critical, at most 1 (critically damped)
MAX_DAMPING = 1.0


@dataclass(frozen=True)
class NoSpecimen(Params):
    """The bare table."""

    kind: str = plain(default="none")
    title: str = plain(default="bare table")
    source: str = plain(default="")

    @property
    def mass(self) -> float:
        return 0.0


@dataclass(frozen=True)
class RigidBlock(Params):
    """A rigid mass anchored to the table (§2.5: three concrete blocks, 70.5 kips)."""

    weight: float = quantity("kip", "weight_kip", minimum=0)
    height: float = quantity("in", "height_in", minimum=0, exclusive=False,
                             doc="centre of gravity above the actuator line")
    size: tuple[float, ...] | None = quantity("in", "size_in", default=None, vector=True,
                                              doc="W x H x L of one block")
    count: int = plain(default=1)
    kind: str = plain(default="rigid")
    title: str = plain(default="rigid block")
    source: str = plain(default="")

    @property
    def mass(self) -> float:
        return self.weight / G


@dataclass(frozen=True)
class SDOFSpecimen(Params):
    """A single-degree-of-freedom structure: lumped mass m_s at height h (eqs 3.3-3.9)."""

    weight: float = quantity("kip", "weight_kip", minimum=0)
    height: float = quantity("in", "height_in", minimum=0, exclusive=False,
                             doc="top mass above the actuator line")
    frequency: float = quantity("Hz", "frequency_hz", minimum=0, doc="fixed-base f_s")
    damping: float = quantity("1", "damping", minimum=0, exclusive=False,
                              maximum=MAX_DAMPING, fraction=True, doc="fixed-base ξ_s")
    kind: str = plain(default="sdof")
    title: str = plain(default="SDOF structure")
    source: str = plain(default="")

    @property
    def mass(self) -> float:
        """m_s (kg)."""
        return self.weight / G

    @property
    def omega(self) -> float:
        """ω_s = 2π f_s (rad/s)."""
        return 2 * math.pi * self.frequency

    @property
    def stiffness(self) -> float:
        """k_s = m_s ω_s² (N/m), eq 3.8."""
        return self.mass * self.omega**2

    @property
    def damping_coefficient(self) -> float:
        """c_s = 2 ξ_s ω_s m_s (N s/m), eq 3.9."""
        return 2 * self.damping * self.omega * self.mass

    @classmethod
    def from_stiffness(cls, weight: float, height: float, k_s: float, c_s: float,
                       **kw: Any) -> SDOFSpecimen:
        """From m_s g, h, k_s and c_s in SI (as Table 5.1 gives them), eqs 3.8-3.9."""
        m = weight / G
        w = math.sqrt(k_s / m)
        return cls(weight=weight, height=height, frequency=w / (2 * math.pi),
                   damping=c_s / (2 * w * m), **kw)


@dataclass(frozen=True)
class ShearBuilding(Params):
    """An n-storey shear building (eq 4.5): storey weights and heights, and either
    storey stiffnesses or fixed-base frequencies; modal damping ξ in every mode."""

    weights: tuple[float, ...] = quantity("kip", "weights_kip", vector=True)
    heights: tuple[float, ...] = quantity("in", "heights_in", vector=True,
                                          doc="floor heights above the actuator line")
    damping: float = quantity("1", "damping", minimum=0, exclusive=False,
                              maximum=MAX_DAMPING, fraction=True)
    stiffnesses: tuple[float, ...] | None = quantity("kip/in", "stiffnesses_kip_per_in",
                                                     default=None, vector=True)
    frequencies: tuple[float, ...] | None = quantity("Hz", "frequencies_hz", default=None,
                                                     vector=True)
    kind: str = plain(default="shear_building")
    title: str = plain(default="shear building")
    source: str = plain(default="")

    def __post_init__(self) -> None:
        n = len(self.weights)
        name = "ShearBuilding"
        if n == 0:
            raise VtableError(f"{name}.weights_kip: needs at least one storey")
        if n > MAX_STOREYS:
            raise VtableError(f"{name}.weights_kip: {n} storeys; vtable models at most "
                              f"{MAX_STOREYS}")
        super().__post_init__()
        if len(self.heights) != n:
            raise VtableError(f"{name}.heights_in: {len(self.heights)} heights for {n} weights")
        if any(not w > 0 for w in self.weights):
            raise VtableError(f"{name}.weights_kip: every weight must be > 0")
        if any(b <= a for a, b in zip(self.heights, self.heights[1:], strict=False)):
            raise VtableError(f"{name}.heights_in: heights must increase upwards")
        if (self.stiffnesses is None) == (self.frequencies is None):
            raise VtableError(f"{name}: give exactly one of stiffnesses_kip_per_in "
                              "and frequencies_hz")
        given = self.stiffnesses if self.stiffnesses is not None else self.frequencies
        key = "stiffnesses_kip_per_in" if self.stiffnesses is not None else "frequencies_hz"
        if len(given) != n:
            raise VtableError(f"{name}.{key}: {len(given)} values for {n} storeys")
        if any(not v > 0 for v in given):
            raise VtableError(f"{name}.{key}: every value must be > 0")

    @property
    def masses(self) -> np.ndarray:
        return np.asarray(self.weights) / G

    @property
    def mass(self) -> float:
        return float(self.masses.sum())

    @property
    def n(self) -> int:
        return len(self.weights)


Specimen = NoSpecimen | RigidBlock | SDOFSpecimen | ShearBuilding
_BY_KIND: dict[str, type] = {"none": NoSpecimen, "rigid": RigidBlock, "sdof": SDOFSpecimen,
                             "shear_building": ShearBuilding}


def specimen_from_dict(d: dict[str, Any], where: str = "specimen") -> Specimen:
    """A specimen from a TOML table whose `kind` picks the class (run-format names)."""
    if not isinstance(d, dict):
        raise VtableError(f"{where}: expected a table")
    kind = d.get("kind")
    if not isinstance(kind, str) or kind not in _BY_KIND:
        raise VtableError(f"{where}.kind: expected one of {', '.join(KINDS)}, got {kind!r}")
    d = dict(d)
    if kind == "shear_building":
        for k in ("weights_kip", "heights_in", "stiffnesses_kip_per_in", "frequencies_hz"):
            if isinstance(d.get(k), list) and len(d[k]) > MAX_STOREYS:
                raise VtableError(f"{where}.{k}: {len(d[k])} storeys; vtable models at most "
                                  f"{MAX_STOREYS}")
    if kind == "sdof" and "stiffness_kip_per_in" in d:
        return _sdof_from_stiffness(d, where)
    return _BY_KIND[kind].from_dict(d, where)


def _sdof_from_stiffness(d: dict[str, Any], where: str) -> SDOFSpecimen:
    """Table 5.1 style: weight, height, k_s (kip/in) and c_s (lb-s/in)."""
    if "damping_lb_s_per_in" not in d:
        raise VtableError(f"{where}: stiffness_kip_per_in needs damping_lb_s_per_in")
    k_s = check_number(d.pop("stiffness_kip_per_in"), f"{where}.stiffness_kip_per_in", "kip/in")
    c_s = check_number(d.pop("damping_lb_s_per_in"), f"{where}.damping_lb_s_per_in", "lb-s/in")
    d.setdefault("frequency_hz", 1.0)
    d.setdefault("damping", 0.0)
    base = SDOFSpecimen.from_dict(d, where)
    if not (k_s > 0 and c_s >= 0):
        raise VtableError(f"{where}: stiffness must be > 0 and damping >= 0")
    return SDOFSpecimen.from_stiffness(base.weight, base.height, k_s, c_s, title=base.title,
                                       source=base.source)
