"""Specimens: none, a rigid block (§2.5), a SDOF structure (§2.4), a shear building.

Heights are measured from the horizontal actuator line (29.7 in below the table top,
§4.2.1), as in the run format; `from_table_top` converts.

Damping ratios are fractions of critical (0.02, not 2 %): a ratio above 1 (an
overdamped structure, or a percentage written as a fraction) is refused. A shear
building has at most `MAX_STOREYS` storeys; its damping is classical (its fixed-base modes
stay its damped modes): one ratio for every mode, one ratio per mode, or Rayleigh damping
C = α M + β K through two anchors (f₁, ξ₁), (f₂, ξ₂).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from vtable.errors import VtableError
from vtable.params.base import Params, check_number, plain, quantity, respelled
from vtable.params.hysteresis import Hysteresis, parse_hysteresis
from vtable.units import G

#: the names `vtable.params` gives (the package's public ones)
__all__ = [
    "NoSpecimen", "RigidBlock", "SDOFSpecimen", "ShearBuilding", "Specimen",
    "specimen_from_dict"
]

KINDS = ("none", "rigid", "sdof", "shear_building", "opensees")
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
                                              minimum=0, doc="W x H x L of one block")
    count: int = plain(default=1)
    kind: str = plain(default="rigid")
    title: str = plain(default="rigid block")
    source: str = plain(default="")

    def __post_init__(self) -> None:
        super().__post_init__()
        if isinstance(self.count, bool) or not isinstance(self.count, int) or self.count < 1:
            raise VtableError(f"count: expected a whole number of blocks >= 1, got "
                              f"{self.count!r}")
        if self.size is not None and len(self.size) != 3:
            raise VtableError(f"size_in: expected 3 numbers (W x H x L of one block), got "
                              f"{len(self.size)}")

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
    #: Bouc–Wen yielding (`vtable.params.hysteresis`); None: elastic
    hysteresis: Hysteresis | None = plain(default=None)

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
    storey stiffnesses or fixed-base frequencies; classical damping given by exactly one of

    - `damping`: one modal ratio ξ for every mode, or a tuple of n ratios, one per
      fixed-base mode, lowest mode first (C = M Φ diag(2 ξ_i ω_i) Φᵀ M);
    - `rayleigh`: Rayleigh damping C = α M + β K through two anchors ((f₁, ξ₁), (f₂, ξ₂))
      (Hz, fraction of critical): ξ(ω) = α/(2ω) + βω/2 passes through both, so mode i has
      ξ_i = ξ(ω_i) (`rayleigh_coefficients`, `damping_ratios`).
    """

    weights: tuple[float, ...] = quantity("kip", "weights_kip", vector=True)
    heights: tuple[float, ...] = quantity("in", "heights_in", vector=True,
                                          doc="floor heights above the actuator line")
    damping: float | tuple[float, ...] | None = quantity(
        "1", "damping", default=None, minimum=0, exclusive=False, maximum=MAX_DAMPING,
        fraction=True, doc="modal ratio: one for every mode, or one per mode")
    stiffnesses: tuple[float, ...] | None = quantity("kip/in", "stiffnesses_kip_per_in",
                                                     default=None, vector=True)
    frequencies: tuple[float, ...] | None = quantity("Hz", "frequencies_hz", default=None,
                                                     vector=True)
    rayleigh: tuple[tuple[float, float], tuple[float, float]] | None = plain(
        "damping_rayleigh", default=None,
        doc="Rayleigh damping through [[f1_hz, xi1], [f2_hz, xi2]]")
    kind: str = plain(default="shear_building")
    title: str = plain(default="shear building")
    source: str = plain(default="")
    #: Bouc–Wen yielding storeys (`vtable.params.hysteresis`); None: elastic
    hysteresis: Hysteresis | None = plain(default=None)

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
        if (self.damping is None) == (self.rayleigh is None):
            raise VtableError(f"{name}: give exactly one of damping and damping_rayleigh")
        if isinstance(self.damping, tuple) and len(self.damping) != n:
            raise VtableError(f"{name}.damping: expected a number, got "
                              f"{list(self.damping)}: a list gives one ratio per mode, "
                              f"{n} here")
        if self.rayleigh is not None:
            self.rayleigh_coefficients()  # checks the anchors

    @property
    def masses(self) -> np.ndarray:
        return np.asarray(self.weights) / G

    @property
    def mass(self) -> float:
        return float(self.masses.sum())

    @property
    def n(self) -> int:
        return len(self.weights)

    def rayleigh_coefficients(self) -> tuple[float, float]:
        """(α, β) of C = α M + β K through the two anchors: ξ(ω) = α/(2ω) + βω/2 equals
        ξ₁ at ω₁ = 2π f₁ and ξ₂ at ω₂ = 2π f₂ (α in 1/s, β in s). Anchors at one
        frequency, or a pair that needs a negative α or β (ξ₂/ξ₁ above ω₂/ω₁, or ξ₂ω₂
        below ξ₁ω₁: a damping matrix that is not positive), are refused."""
        where = "ShearBuilding.damping_rayleigh"
        if self.rayleigh is None:
            raise VtableError(f"{where}: not given")
        (f1, x1), (f2, x2) = sorted(self.rayleigh)
        w1, w2 = 2 * math.pi * f1, 2 * math.pi * f2
        if not w2 > w1 * (1 + 1e-9):
            raise VtableError(f"{where}: the two anchors need two different frequencies, "
                              f"got {f1:g} and {f2:g} Hz")
        alpha, beta = np.linalg.solve([[1 / (2 * w1), w1 / 2], [1 / (2 * w2), w2 / 2]],
                                      [x1, x2])
        tol = 1e-9 * max(x1, x2)  # rounding of an α or β that is exactly zero
        if alpha < -tol * w1 or beta < -tol / w2:
            raise VtableError(f"{where}: ξ {x1:g} at {f1:g} Hz and {x2:g} at {f2:g} Hz need "
                              f"a negative {'α' if alpha < 0 else 'β'} (α {alpha:.3g} 1/s, "
                              f"β {beta:.3g} s): Rayleigh damping cannot pass through them")
        return float(max(alpha, 0.0)), float(max(beta, 0.0))

    def damping_ratios(self, omega: np.ndarray) -> np.ndarray:
        """Each fixed-base mode's damping ratio, the modes' circular frequencies `omega`
        (rad/s) ascending: the one ratio repeated, the per-mode ratios, or Rayleigh's
        ξ_i = α/(2ω_i) + βω_i/2."""
        omega = np.asarray(omega, dtype=float)
        if self.rayleigh is not None:
            alpha, beta = self.rayleigh_coefficients()
            return alpha / (2 * omega) + beta * omega / 2
        return np.broadcast_to(np.asarray(self.damping, dtype=float), omega.shape).copy()

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str = "") -> ShearBuilding:
        """The TOML table; `damping` one ratio or a list (one per mode), or
        `damping_rayleigh = [[f1_hz, xi1], [f2_hz, xi2]]`."""
        where = where or cls.__name__
        if not isinstance(d, dict):
            raise VtableError(f"{where}: expected a table, got {type(d).__name__}")
        d = dict(d)
        per_mode = anchors = None
        xi = d.get("damping")
        if isinstance(xi, list):
            n = len(d["weights_kip"]) if isinstance(d.get("weights_kip"), list) else None
            if not xi or (n is not None and len(xi) != n):
                raise VtableError(f"{where}.damping: expected a number, got {xi!r}: a list "
                                  "gives one ratio per mode" + (f", {n} here" if n else ""))
            per_mode = tuple(check_number(x, f"{where}.damping[{i}]")
                             for i, x in enumerate(xi))
            d["damping"] = 0.0  # checked below, with the per-mode ratios in place
        if "damping_rayleigh" in d:
            if "damping" in d:
                raise VtableError(f"{where}: give exactly one of damping and damping_rayleigh")
            anchors = _rayleigh_anchors(d.pop("damping_rayleigh"), f"{where}.damping_rayleigh")
            d["damping"] = 0.0
        base = super().from_dict(d, where)
        if per_mode is None and anchors is None:
            return base
        try:
            return dataclasses.replace(base, damping=per_mode, rayleigh=anchors)
        except VtableError as e:
            raise VtableError(f"{where}: {e}") from None

    def to_dict(self) -> dict[str, Any]:
        d = super().to_dict()
        if self.rayleigh is not None:
            d["damping_rayleigh"] = [list(a) for a in self.rayleigh]
        return d


def _rayleigh_anchors(v: Any, where: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """[[f1_hz, xi1], [f2_hz, xi2]] -> two (Hz, ratio) pairs, each checked."""
    if not (isinstance(v, list | tuple) and len(v) == 2
            and all(isinstance(a, list | tuple) and len(a) == 2 for a in v)):
        raise VtableError(f"{where}: expected [[f1_hz, xi1], [f2_hz, xi2]], got {v!r:.60}")
    out = []
    for i, (f, xi) in enumerate(v):
        f = check_number(f, f"{where}[{i}][0]", "Hz")
        xi = check_number(xi, f"{where}[{i}][1]")
        if not f > 0:
            raise VtableError(f"{where}[{i}][0]: a frequency must be > 0, got {f:g}")
        if not 0 <= xi <= MAX_DAMPING:
            raise VtableError(f"{where}[{i}][1] is a fraction of critical damping, from 0 "
                              f"to {MAX_DAMPING:g}; got {xi:g} ({xi:g} means {100 * xi:g} %)")
        out.append((f, xi))
    return out[0], out[1]


#: the keys of an OpenSees specimen's model as data (`OpenSeesSpecimen.building`): its
#: equivalent shear building's, written into a run by `vtable simulate`
OPENSEES_DATA_KEYS = ("weights_kip", "heights_in", "frequencies_hz", "damping")


@dataclass(frozen=True)
class OpenSeesSpecimen(Params):
    """Any openseespy model (`model`: a Python file defining ``build(ops)``, see
    `vtable.opensees.model`), stepped by the virtual table with the platen
    (`vtable.opensees.stepper`) when `vtable simulate` runs it.

    `building` is the model as data: its floors' masses and heights, its first lateral
    fixed-base modes and their damping, as the equivalent shear building a run file holds
    (`OPENSEES_DATA_KEYS` beside `model` in [specimen]). `vtable simulate` writes it
    (`vtable.opensees.equivalent`); every reader of a run takes it from there and never
    runs the model file. None: not known yet (a specimen file that only names the model).
    """

    model: str = plain(doc="the model's Python file (relative to the TOML file)")
    kind: str = plain(default="opensees")
    title: str = plain(default="OpenSees model")
    source: str = plain(default="")
    building: ShearBuilding | None = plain(default=None, toml=False)

    @property
    def mass(self) -> float:
        if self.building is None:
            raise VtableError(f"the OpenSees specimen {Path(self.model).name}: its masses "
                              "are not known until the model is built (vtable simulate)")
        return self.building.mass

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str = "") -> OpenSeesSpecimen:
        """`model`, `title`, `source` and, when present, the model as data
        (`OPENSEES_DATA_KEYS`, all of them: a shear building's keys)."""
        where = where or cls.__name__
        d = dict(d)
        data = {k: d.pop(k) for k in OPENSEES_DATA_KEYS if k in d}
        base = super().from_dict(d, where)
        if not data:
            return base
        missing = [k for k in OPENSEES_DATA_KEYS if k not in data]
        if missing:
            raise VtableError(f"{where}: the model as data needs {', '.join(missing)} too "
                              f"(with {', '.join(data)}; vtable simulate writes all "
                              f"{len(OPENSEES_DATA_KEYS)})")
        b = ShearBuilding.from_dict({**data, "title": f"{base.title} (as a shear building)",
                                     "source": base.model}, where)
        return dataclasses.replace(base, building=b)


Specimen = NoSpecimen | RigidBlock | SDOFSpecimen | ShearBuilding | OpenSeesSpecimen
_BY_KIND: dict[str, type] = {"none": NoSpecimen, "rigid": RigidBlock, "sdof": SDOFSpecimen,
                             "shear_building": ShearBuilding, "opensees": OpenSeesSpecimen}


#: a structural damping ratio at or above this is legal but suspicious (structures on a
#: table are at 0.005-0.10 of critical): said, with the likely slip (a percentage)
SUSPICIOUS_DAMPING = 0.5


def specimen_hints(specimen: Specimen, where: str = "specimen") -> list[str]:
    """Notes on a legal specimen: declared hysteresis (which models realise it), and a
    damping ratio ≥ `SUSPICIOUS_DAMPING` (likely a percentage written as a number: 5 for
    5 %, 1 for 1 %)."""
    out = []
    h = getattr(specimen, "hysteresis", None)
    if h is not None:
        out.append(f"{where}.hysteresis: storey(s) {', '.join(map(str, h.storeys))} yield "
                   "(Bouc–Wen) in the reduced model and the virtual table; the analytical "
                   "models (modes, margins, assess's linear models) use the initial stiffness")
    ratios = getattr(specimen, "damping", None)
    if ratios is None:
        return out
    ratios = ratios if isinstance(ratios, tuple) else (ratios,)
    for k, z in enumerate(ratios):
        if z >= SUSPICIOUS_DAMPING:
            key = "damping" if len(ratios) == 1 else f"damping[{k}]"
            out.append(f"{where}.{key} = {z:g} is {z:.0%} of critical, taken as given; "
                       f"structures on a table have 0.5-10 %: if {z:g} % is meant, write "
                       f"{z / 100:g}")
    return out


def specimen_from_dict(d: dict[str, Any], where: str = "specimen",
                       folder: Path | None = None) -> Specimen:
    """A specimen from a TOML table whose `kind` picks the class (run-format names); an
    OpenSees model's file is found relative to `folder` (the TOML file's), never run
    (reading is data only: `vtable.opensees.equivalent.realised` runs it, for simulate)."""
    if not isinstance(d, dict):
        raise VtableError(f"{where}: expected a table")
    kind = d.get("kind")
    if not isinstance(kind, str) or kind not in _BY_KIND:
        raise VtableError(f"{where}.kind: expected one of {', '.join(KINDS)}, got {kind!r}")
    d = dict(d)
    hyst = d.pop("hysteresis", None)
    if hyst is not None and kind not in ("sdof", "shear_building"):
        raise VtableError(f"{where}.hysteresis: only a sdof or shear_building specimen has "
                          f"storeys that yield, not {kind!r}")
    spec = _specimen(kind, d, where)
    if isinstance(spec, OpenSeesSpecimen):  # found, never run: only `simulate` runs it
        path = Path(spec.model)
        if folder is not None and not path.is_absolute():
            path = folder / path
        spec = dataclasses.replace(spec, model=str(path.resolve()) if path.is_file()
                                   else str(path))
    if hyst is None:
        return spec
    h = parse_hysteresis(hyst, len(spec.weights) if isinstance(spec, ShearBuilding) else 1,
                         f"{where}.hysteresis")
    return dataclasses.replace(spec, hysteresis=h)


#: a specimen's keys in other units (`params.base.respelled`): the run format's key -> (its
#: unit, {another key: its unit}, whether it takes a list); the format's spec lets every
#: key name SI instead
_WEIGHT = {"mass_kg": "kg", "weight_lb": "lb", "weight_n": "N", "weight_kn": "kN"}
SPELLINGS: dict[str, tuple[str, dict[str, str], bool]] = {
    "weight_kip": ("kip", _WEIGHT, False),
    "height_in": ("in", {"height_m": "m", "height_mm": "mm"}, False),
    "size_in": ("in", {"size_m": "m", "size_mm": "mm"}, True),
    "weights_kip": ("kip", {"masses_kg": "kg", "weights_lb": "lb", "weights_n": "N",
                            "weights_kn": "kN"}, True),
    "heights_in": ("in", {"heights_m": "m", "heights_mm": "mm"}, True),
    "stiffness_kip_per_in": ("kip/in", {"stiffness_n_per_m": "N/m",
                                        "stiffness_lb_per_in": "lb/in"}, False),
    "stiffnesses_kip_per_in": ("kip/in", {"stiffnesses_n_per_m": "N/m",
                                          "stiffnesses_lb_per_in": "lb/in"}, True),
    "damping_lb_s_per_in": ("lb-s/in", {"damping_n_s_per_m": "N-s/m",
                                        "damping_kip_s_per_in": "kip-s/in"}, False),
}
#: the Table 5.1 way of an sdof (`_sdof_from_stiffness`): keys of no field
_TABLE_5_1 = ("stiffness_kip_per_in", "damping_lb_s_per_in")


def _specimen(kind: str, d: dict[str, Any], where: str) -> Specimen:
    takes = {f.metadata.get("key") or f.name for f in dataclasses.fields(_BY_KIND[kind])}
    takes |= set(_TABLE_5_1) if kind == "sdof" else set()
    # only the kind's own keys are respelled: another's stays as given, an unknown key
    d = respelled(d, {k: v for k, v in SPELLINGS.items() if k in takes}, where)
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
