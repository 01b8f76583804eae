"""Calibrating the base: what a lab only approximately knows, refitted within bounds around
its declaration (docs/effects.md: "a difference that such a calibration absorbs is
a wrong declaration, not a missing effect").

The base parameters of a campaign (`base_params`):

- the servo loop (f_o, ξ_o, k_o) of eq 6.15: free within wide bounds, no prior (Table B.5
  through eq 6.16 is a design value, not a measurement);
- each specimen mode's fixed-base frequency (declared ± `Calibration.frequency`), each
  mode's damping ratio (declared ×/÷ `Calibration.damping`, every mode on its own: a
  building declared with one ratio, or Rayleigh damping, is fitted one ratio per mode) and
  its mass (± `Calibration.mass`; a building's storeys
  each on their own; the frequencies are held, so the stiffnesses follow);
- the platen's mass (± `Calibration.mass`);
- a declared digital controller's terms its kind lets a diagnosis refit
  (`vtable.controllers.kinds.ControllerKind.calibrated`: the feedforward gains, the
  acceleration feedback), each within its factor bounds of the declared value (×/÷ 2)
  with a log prior of half the wider side — a lab's drive may be scaled or its
  feedforward tuned off the value it wrote down;
- when the model lets the platen pitch: the platen's centre-of-mass height above the
  horizontal actuator line (anywhere from the line itself to `Calibration.com_height` ×
  the declared height; the report's models put it on the line, eqs 7.7, 8.16) and its
  pitch inertia (declared ×/÷ `Calibration.pitch_inertia`).

Priors: a declared parameter p with prior width σ adds the residual
λ (p - p_declared)/σ, λ = `Calibration.prior_weight` × noise floor × √(channel groups):
moving one σ costs what an error of 0.3 × the noise floor would, so a parameter stays
near its declaration unless the data insist. σ is half the bound (frequency ±2.5 %, mass
±5 %, damping ×/÷√3 on the log scale, pitch inertia likewise); the centre-of-mass height and
the servo loop carry none.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from vtable.analytic.structure import modal_damping, specimen_frequencies
from vtable.errors import VtableError
from vtable.models.physics import Physics, nominal_open_loop
from vtable.params.specimen import (
    NoSpecimen,
    RigidBlock,
    SDOFSpecimen,
    ShearBuilding,
)
from vtable.params.virtual import VirtualTable
from vtable.tables.bodies import slab_body
from vtable.units import G

#: the servo loop's bounds: name -> (JSON key, unit, lower, upper)
LOOP = {"f_o": ("servo_loop.f_o_hz", "Hz", 1.0, 100.0),
        "xi_o": ("servo_loop.xi_o", "1", 0.02, 5.0),
        "k_o": ("servo_loop.k_o_per_s", "1/s", 1.0, 500.0)}


@dataclass(frozen=True)
class Calibration:
    """How far the base may move from the declaration (see the module docstring).

    Parameters
    ----------
    frequency
        Relative bound on each specimen mode's frequency (0.05: ±5 %).
    damping
        Factor bound on each specimen mode's damping ratio (3: declared ×/÷ 3).
    mass
        Relative bound on the specimen's and the platen's masses (0.10: ±10 %).
    com_height
        Upper bound of the platen's centre-of-mass height, × the declared (lower bound 0).
    pitch_inertia
        Factor bound on the platen's pitch inertia.
    prior_weight
        λ / (noise floor × √groups) of the priors; 0: no priors.
    enabled
        False: only the servo loop is fitted (the declarations are taken as exact).
    """

    frequency: float = 0.05
    damping: float = 3.0
    mass: float = 0.10
    com_height: float = 2.0
    pitch_inertia: float = 1.5
    prior_weight: float = 0.3
    enabled: bool = True

    def __post_init__(self) -> None:
        for name, lo, hi in (("frequency", 0.0, 0.5), ("damping", 1.0, 100.0),
                             ("mass", 0.0, 0.9), ("com_height", 0.0, 100.0),
                             ("pitch_inertia", 1.0, 100.0), ("prior_weight", 0.0, 100.0)):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and lo <= v <= hi):
                raise VtableError(f"calibration {name}: expected a number from {lo:g} to "
                                  f"{hi:g}, got {v!r}")

    @classmethod
    def parse(cls, text: str) -> Calibration:
        """'none' or 'frequency=0.03,damping=2,...' (the CLI's --calibrate)."""
        if text.strip().lower() == "none":
            return cls(enabled=False)
        kw: dict[str, float] = {}
        names = [f.name for f in dataclasses.fields(cls) if f.name != "enabled"]
        for part in filter(None, (p.strip() for p in text.split(","))):
            key, sep, value = part.partition("=")
            key = key.strip()
            if not sep or key not in names:
                raise VtableError(f"--calibrate: {part!r}: expected NAME=VALUE with NAME one "
                                  f"of {', '.join(names)}, or 'none'")
            try:
                kw[key] = float(value)
            except ValueError:
                raise VtableError(f"--calibrate {key}: {value!r} is not a number") from None
        return cls(**kw)

    def text(self) -> str:
        """The --calibrate text of this calibration: the settings that differ from the
        defaults ('' for the defaults, 'none' when disabled); `parse(text())` gives it
        back."""
        if not self.enabled:
            return "none"
        default = Calibration()
        return ",".join(f"{f.name}={getattr(self, f.name):g}" for f in dataclasses.fields(self)
                        if f.name != "enabled" and getattr(self, f.name) != getattr(default,
                                                                                    f.name))

    def widened(self, names: Sequence[str]) -> Calibration:
        """This calibration with the bounds `names` widened: a relative bound doubled, a
        factor bound squared, each within its allowed range."""
        kw = {}
        for name in dict.fromkeys(names):
            v, (kind, top) = getattr(self, name), WIDEN[name]
            kw[name] = min(v * v if kind == "factor" else 2 * v, top)
        return dataclasses.replace(self, **kw)


#: each bound of the calibration: how it bounds ("relative": ± x, "factor": ×/÷ x, "upper":
#: up to x × the declared), and the largest value it may take
WIDEN = {"frequency": ("relative", 0.5), "damping": ("factor", 100.0),
         "mass": ("relative", 0.9), "com_height": ("upper", 100.0),
         "pitch_inertia": ("factor", 100.0)}


def bounding_setting(key: str, side: str) -> str | None:
    """The `Calibration` bound (a --calibrate NAME) that bounds base parameter `key` on
    `side` ("lower" or "upper"); None for the servo loop (fixed wide bounds) and for the
    centre-of-mass height's lower bound (the actuator line itself)."""
    owner, _, name = key.partition(".")
    if owner == "servo_loop":
        return None
    if name.endswith("frequency_hz"):
        return "frequency"
    if name.endswith("damping"):
        return "damping"
    if name.endswith("mass_kg"):
        return "mass"
    if name == "com_height_m":
        return "com_height" if side == "upper" else None
    if name == "pitch_inertia_kg_m2":
        return "pitch_inertia"
    return None


@dataclass(frozen=True)
class BaseParam:
    """One calibrated base parameter (values in the unit of `key`)."""

    key: str
    unit: str
    declared: float
    lower: float
    upper: float
    log: bool
    prior: float | None  # σ on the fitted scale (the log for log parameters); None: none
    group: str           # "loop", "specimen", "table", "pitch"
    get: Callable[[Physics], float] = dataclasses.field(repr=False)
    set: Callable[[Physics, float], Physics] = dataclasses.field(repr=False)


def _loop_param(name: str, declared: float) -> BaseParam:
    key, unit, lo, hi = LOOP[name]

    def get(ph: Physics) -> float:
        return float(getattr(ph.open_loop, name))

    def put(ph: Physics, v: float) -> Physics:
        return dataclasses.replace(ph, open_loop=dataclasses.replace(ph.open_loop, **{name: v}))

    return BaseParam(key, unit, declared, lo, hi, True, None, "loop", get, put)


def _with_frequency(spec, i: int, f: float):
    if isinstance(spec, SDOFSpecimen):
        return dataclasses.replace(spec, frequency=f)
    fs = list(specimen_frequencies(spec))
    fs[i] = f
    return dataclasses.replace(spec, stiffnesses=None, frequencies=tuple(fs))


def _frequency_form(spec):
    """A building declared by storey stiffnesses, as its fixed-base frequencies (held when a
    storey's mass is calibrated: the frequencies are what the calibration moves)."""
    if spec.stiffnesses is None:
        return spec
    return dataclasses.replace(spec, stiffnesses=None,
                               frequencies=tuple(specimen_frequencies(spec)))


def _mass_of(spec) -> float:
    return float(spec.mass)


def _with_mass(spec, m: float):
    s = m / _mass_of(spec)
    if isinstance(spec, ShearBuilding):
        if spec.stiffnesses is not None:  # hold the frequencies: scale the stiffnesses too
            spec = dataclasses.replace(spec, stiffnesses=tuple(k * s for k in spec.stiffnesses))
        return dataclasses.replace(spec, weights=tuple(w * s for w in spec.weights))
    return dataclasses.replace(spec, weight=spec.weight * s)


def _mode_damping(spec) -> list[float]:
    """Each fixed-base mode's damping ratio (a SDOF: its one mode), lowest mode first."""
    if isinstance(spec, SDOFSpecimen):
        return [float(spec.damping)]
    if isinstance(spec.damping, tuple):
        return list(spec.damping)
    return [float(x) for x in modal_damping(spec)]


def _with_mode_damping(spec, i: int, xi: float):
    """`spec` with mode i's damping ratio at `xi`, the other modes' held: a building's
    damping becomes one ratio per mode (Rayleigh's included, at the modes' ratios now)."""
    if isinstance(spec, SDOFSpecimen):
        return dataclasses.replace(spec, damping=xi)
    ratios = _mode_damping(spec)
    ratios[i] = xi
    return dataclasses.replace(spec, damping=tuple(ratios), rayleigh=None)


def _damping_params(spec, cal: Calibration) -> list[BaseParam]:
    """Each mode's damping ratio, declared ×/÷ `cal.damping` with a log prior of half that
    width times √(modes) — the priors of n modes together pull as one ratio's did — (a
    SDOF's one ratio is `specimen.damping`, a building's mode K's `specimen.modeK.damping`);
    an undamped mode is held at zero."""
    out = []
    ratios = _mode_damping(spec)
    widen = math.sqrt(sum(1 for xi in ratios if xi > 0) or 1)
    for i, xi in enumerate(ratios):
        if not xi > 0:
            continue
        key = ("specimen.damping" if isinstance(spec, SDOFSpecimen)
               else f"specimen.mode{i + 1}.damping")

        def get(ph: Physics, i: int = i) -> float:
            return float(_mode_damping(ph.specimen)[i])

        def put(ph: Physics, v: float, i: int = i) -> Physics:
            return dataclasses.replace(ph, specimen=_with_mode_damping(ph.specimen, i, v))

        out.append(BaseParam(key, "1", xi, xi / cal.damping, min(xi * cal.damping, 0.99),
                             True, widen * math.log(cal.damping) / 2 or None, "specimen", get,
                             put))
    return out


def specimen_params(spec, cal: Calibration) -> list[BaseParam]:
    """The specimen's calibrated parameters (frequencies, damping, masses) declared `spec`."""
    out: list[BaseParam] = []
    if isinstance(spec, NoSpecimen):
        return out
    if isinstance(spec, SDOFSpecimen | ShearBuilding):
        fs = list(specimen_frequencies(spec))
        for i, f0 in enumerate(fs):
            key = ("specimen.frequency_hz" if isinstance(spec, SDOFSpecimen)
                   else f"specimen.mode{i + 1}.frequency_hz")

            def get(ph: Physics, i: int = i) -> float:
                return float(specimen_frequencies(ph.specimen)[i])

            def put(ph: Physics, v: float, i: int = i) -> Physics:
                return dataclasses.replace(ph, specimen=_with_frequency(ph.specimen, i, v))

            out.append(BaseParam(key, "Hz", f0, f0 * (1 - cal.frequency),
                                 f0 * (1 + cal.frequency), False,
                                 f0 * cal.frequency / 2 or None, "specimen", get, put))
        out += _damping_params(spec, cal)
    if isinstance(spec, ShearBuilding) and spec.n > 1:  # each storey's mass on its own
        for j, w0 in enumerate(spec.weights):
            m0 = w0 / G

            def get_s(ph: Physics, j: int = j) -> float:
                return float(ph.specimen.masses[j])

            def put_s(ph: Physics, v: float, j: int = j) -> Physics:
                sp = _frequency_form(ph.specimen)
                w = list(sp.weights)
                w[j] = v * G
                return dataclasses.replace(ph, specimen=dataclasses.replace(sp, weights=tuple(w)))

            out.append(BaseParam(f"specimen.storey{j + 1}.mass_kg", "kg", m0,
                                 m0 * (1 - cal.mass), m0 * (1 + cal.mass), False,
                                 m0 * cal.mass / 2 or None, "specimen", get_s, put_s))
    elif isinstance(spec, SDOFSpecimen | ShearBuilding | RigidBlock):
        m0 = _mass_of(spec)

        def get_m(ph: Physics) -> float:
            return _mass_of(ph.specimen)

        def put_m(ph: Physics, v: float) -> Physics:
            return dataclasses.replace(ph, specimen=_with_mass(ph.specimen, v))

        out.append(BaseParam("specimen.mass_kg", "kg", m0, m0 * (1 - cal.mass),
                             m0 * (1 + cal.mass), False, m0 * cal.mass / 2 or None, "specimen",
                             get_m, put_m))
    return [p for p in out if p.upper > p.lower]


def _table_value(name: str, vt: VirtualTable) -> float:
    if name == "platen_mass":
        return float(vt.table.geometry.mass)
    if name == "com_height":
        return float(slab_body(vt).com[2])
    return float(vt.table.geometry.pitch_inertia)


def _table_param(name: str, key: str, unit: str, declared: float, lo: float, hi: float,
                 log: bool, prior: float | None, group: str, vt: VirtualTable) -> BaseParam:
    def get(ph: Physics) -> float:
        return float(ph.table.get(name, _table_value(name, vt)))

    def put(ph: Physics, v: float) -> Physics:
        return dataclasses.replace(ph, table={**ph.table, name: v})

    return BaseParam(key, unit, declared, lo, hi, log, prior, group, get, put)


def _control_param(name: str, declared: float, lo: float, hi: float,
                   unit: str = "1") -> BaseParam:
    """A declared controller's stage parameter, declared ×(lo..hi) with a log prior of
    half the wider side."""
    key = f"control.{name}"

    def get(ph: Physics) -> float:
        return float(ph.table.get(key, declared))

    def put(ph: Physics, v: float) -> Physics:
        return dataclasses.replace(ph, table={**ph.table, key: v})

    prior = max(math.log(hi), -math.log(lo)) / 2
    return BaseParam(f"controller.{name}", unit, declared, declared * lo, declared * hi, True,
                     prior, "loop", get, put)


def base_params(spec, vt: VirtualTable, cal: Calibration, *, pitch: bool,
                loop_declared=None) -> list[BaseParam]:
    """The calibrated base of a campaign whose runs declare `spec` on table `vt`; `pitch`:
    the model lets the platen pitch (adds its centre-of-mass height and pitch inertia)."""
    nominal = loop_declared or nominal_open_loop(vt)
    out = [_loop_param(n, getattr(nominal, n)) for n in LOOP]
    if not cal.enabled:
        return out
    out += specimen_params(spec, cal)
    m0 = _table_value("platen_mass", vt)
    out.append(_table_param("platen_mass", "table.platen_mass_kg", "kg", m0,
                            m0 * (1 - cal.mass), m0 * (1 + cal.mass), False,
                            m0 * cal.mass / 2 or None, "table", vt))
    if vt.control is not None:  # the declared controller's terms a lab may have off
        for name, (lo, hi, *unit) in vt.control.calibrated.items():
            v0 = vt.control.params[name]
            if v0 > 0:
                out.append(_control_param(name, v0, lo, hi, *unit))
    if pitch:
        h0 = _table_value("com_height", vt)
        if h0 > 0:
            out.append(_table_param("com_height", "table.com_height_m", "m", h0, 0.0,
                                    h0 * cal.com_height, False, None, "pitch", vt))
        j0 = _table_value("pitch_inertia", vt)
        out.append(_table_param("pitch_inertia", "table.pitch_inertia_kg_m2", "kg m2", j0,
                                j0 / cal.pitch_inertia, j0 * cal.pitch_inertia, True,
                                math.log(cal.pitch_inertia) / 2 or None, "pitch", vt))
    return [p for p in out if p.upper > p.lower]
