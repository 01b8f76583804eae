"""The report's units <-> SI, used only at the edges (TOML files, CLI output, runs).

Inside vtable everything is SI: m, kg, s, N, Pa, rad. The report (UCB/EERC-91/13) works
in inches, kips, kip-in-s², psi, in³/s/psi and g; those names are the keys of `UNITS`.
Weights given in kip or lb are forces; `weight_to_mass` turns them into masses.

A unit is also read in the other spellings labs write (`canonical`): a power as ``^2`` or
``²`` (``m/s^2``, ``m/s²`` for ``m/s2``) and a product's dot as ``·`` or ``*`` (``kg·m²``
for ``kg-m2``); the messages name the spellings of `UNITS`.
"""

from __future__ import annotations

import numpy as np

from vtable.errors import VtableError

INCH = 0.0254  # m, exact
FOOT = 12 * INCH
LBF = 4.4482216152605  # N, exact (avoirdupois pound x standard gravity)
KIP = 1000 * LBF
PSI = LBF / INCH**2
G = 9.80665  # m/s², standard gravity (the run format's 1 g = 386.09 in/s²)
GALLON = 231 * INCH**3  # US gallon, m³

#: factor that converts a value in the named unit to SI, and the unit's dimension
_TABLE: dict[str, tuple[float, str]] = {
    # length
    "m": (1.0, "length"), "mm": (1e-3, "length"), "cm": (1e-2, "length"),
    "in": (INCH, "length"), "ft": (FOOT, "length"),
    # area, volume
    "m2": (1.0, "area"), "in2": (INCH**2, "area"), "m3": (1.0, "volume"),
    "in3": (INCH**3, "volume"),
    # force
    "N": (1.0, "force"), "kN": (1e3, "force"), "lb": (LBF, "force"), "kip": (KIP, "force"),
    # mass
    "kg": (1.0, "mass"), "lb-s2/in": (LBF / INCH, "mass"), "kip-s2/in": (KIP / INCH, "mass"),
    # rotational inertia
    "kg-m2": (1.0, "rotational inertia"), "kip-in-s2": (KIP * INCH, "rotational inertia"),
    "lb-in-s2": (LBF * INCH, "rotational inertia"),
    # pressure
    "Pa": (1.0, "pressure"), "kPa": (1e3, "pressure"), "MPa": (1e6, "pressure"),
    "psi": (PSI, "pressure"),
    # stiffness and damping
    "N/m": (1.0, "stiffness"), "kip/in": (KIP / INCH, "stiffness"),
    "lb/in": (LBF / INCH, "stiffness"),
    "N-s/m": (1.0, "damping"), "lb-s/in": (LBF / INCH, "damping"),
    "kip-s/in": (KIP / INCH, "damping"),
    "N-m/rad": (1.0, "rotational stiffness"), "lb-in/rad": (LBF * INCH, "rotational stiffness"),
    "kip-in/rad": (KIP * INCH, "rotational stiffness"),
    "N-m-s/rad": (1.0, "rotational damping"), "lb-in-s/rad": (LBF * INCH, "rotational damping"),
    "kip-in-s/rad": (KIP * INCH, "rotational damping"),
    # moment
    "N-m": (1.0, "moment"), "kip-ft": (KIP * FOOT, "moment"), "kip-in": (KIP * INCH, "moment"),
    # kinematics
    "m/s": (1.0, "velocity"), "cm/s": (1e-2, "velocity"), "mm/s": (1e-3, "velocity"),
    "in/s": (INCH, "velocity"),
    "m/s2": (1.0, "acceleration"), "cm/s2": (1e-2, "acceleration"),
    "mm/s2": (1e-3, "acceleration"), "in/s2": (INCH, "acceleration"), "g": (G, "acceleration"),
    "rad": (1.0, "angle"), "deg": (np.pi / 180, "angle"),
    "rad/s": (1.0, "angular velocity"), "deg/s": (np.pi / 180, "angular velocity"),
    "rad/s2": (1.0, "angular acceleration"), "deg/s2": (np.pi / 180, "angular acceleration"),
    # hydraulics
    "m3/s": (1.0, "flow"), "in3/s": (INCH**3, "flow"), "gpm": (GALLON / 60, "flow"),
    "m3/s/Pa": (1.0, "flow-pressure coefficient"),
    "in3/s/psi": (INCH**3 / PSI, "flow-pressure coefficient"),
    # flow per unit displacement error (k_t)
    "m2/s": (1.0, "flow gain"), "in2/s": (INCH**2, "flow gain"),
    # pressure-feedback gain (k_p)
    "m/Pa": (1.0, "pressure-feedback gain"), "in/psi": (INCH / PSI, "pressure-feedback gain"),
    # servovalve and controller gains in volts
    "m3/s/V": (1.0, "valve flow gain"), "in3/s/V": (INCH**3, "valve flow gain"),
    "V/m": (1.0, "displacement gain"), "V/in": (1 / INCH, "displacement gain"),
    "V-s/m": (1.0, "velocity gain"), "V-s/in": (1 / INCH, "velocity gain"),
    "V-s2/m": (1.0, "acceleration gain"), "V-s2/in": (1 / INCH, "acceleration gain"),
    "V/Pa": (1.0, "pressure gain"), "V/psi": (1 / PSI, "pressure gain"),
    # time, frequency, dimensionless
    "s": (1.0, "time"), "ms": (1e-3, "time"), "s2": (1.0, "time squared"),
    "1/s": (1.0, "frequency"), "Hz": (1.0, "frequency"),
    "1": (1.0, "dimensionless"), "%": (0.01, "dimensionless"),
    # per unit length (e.g. a damping ratio rising per inch of drift)
    "1/m": (1.0, "inverse length"), "1/in": (1 / INCH, "inverse length"),
}

#: factor that converts a value in the named unit to SI
UNITS: dict[str, float] = {u: f for u, (f, _) in _TABLE.items()}
#: the physical dimension of every unit (a channel or key accepts only its dimension)
DIMENSIONS: dict[str, str] = {u: d for u, (_, d) in _TABLE.items()}

#: Largest magnitude (SI) vtable accepts for a value of each dimension. Far beyond any
#: shaking-table test (the EERC table: 5 in stroke, 1.5 g, 130 kip payload, Table 2.2), so
#: only absurd values (a unit mix-up by 10^6, 1e308, an overflow) are refused: lengths
#: 10 km, masses 1e9 kg, forces 1e10 N, accelerations 1e5 m/s² (10^4 g), frequencies
#: 10 kHz, times 1e11 s (epoch time stamps fit), dimensionless 1e15 (exact integers).
PLAUSIBLE_MAX: dict[str, float] = {
    "length": 1e4, "area": 1e4, "volume": 1e6, "force": 1e10, "mass": 1e9,
    "rotational inertia": 1e12, "pressure": 1e10, "stiffness": 1e13, "damping": 1e12,
    "rotational stiffness": 1e15, "rotational damping": 1e14, "moment": 1e12,
    "velocity": 1e4, "acceleration": 1e5, "angle": 1e4, "angular velocity": 1e5,
    "angular acceleration": 1e7, "flow": 1e3, "flow-pressure coefficient": 1.0,
    "flow gain": 1e3, "pressure-feedback gain": 1.0, "valve flow gain": 1e3,
    "displacement gain": 1e9, "velocity gain": 1e9, "acceleration gain": 1e9,
    "pressure gain": 1.0, "time squared": 1e6, "time": 1e11, "frequency": 1e4,
    "dimensionless": 1e15, "inverse length": 1e6,
}

#: the smallest magnitude a non-zero value of these dimensions may have: a loop gain or a
#: frequency of 1e-300 1/s is a slip (its time constant outlives the universe) that would
#: otherwise pass as "> 0" and end as a 300-digit margin or a pole read as unstable
PLAUSIBLE_MIN: dict[str, float] = {"frequency": 1e-6}

#: how a quantity of each dimension is called in messages ("avg_hdisp is a displacement")
_NOUN = {"length": "displacement", "angle": "rotation"}


#: the other spellings of a power and a product (`canonical`)
_SPELLINGS = (("^2", "2"), ("^3", "3"), ("\u00b2", "2"), ("\u00b3", "3"), ("\u00b7", "-"),
              ("*", "-"))


def canonical(unit: str) -> str:
    """`unit` in the spelling of `UNITS` (``m/s^2``, ``m/s²`` -> ``m/s2``; ``kg·m²`` ->
    ``kg-m2``); a spelling of no known unit is returned as given."""
    if not isinstance(unit, str) or unit in UNITS:  # (a model build's hot path: one lookup)
        return unit
    u = unit
    for a, b in _SPELLINGS:
        u = u.replace(a, b)
    return u if u in UNITS else unit


def known(unit) -> bool:
    """Whether `unit` (in any spelling `canonical` reads) is a unit vtable knows."""
    return isinstance(unit, str) and canonical(unit) in UNITS


def noun(dim: str) -> str:
    """What a quantity of dimension `dim` is called in messages (length -> displacement)."""
    return _NOUN.get(dim, dim)


def dimension(unit: str) -> str:
    """The dimension of `unit` (length, acceleration, force, ...); unknown is an error."""
    factor(unit)
    return DIMENSIONS[canonical(unit)]


def _article(word: str) -> str:
    return ("an " if word[0] in "aeiou" else "a ") + word


def check_dimension(unit: str, dim: str, what: str) -> None:
    """Refuse `unit` for `what`, a quantity of dimension `dim`, unless the dimensions agree:
    'avg_hdisp is a displacement; 'g' is an acceleration unit'."""
    got = dimension(unit)
    if got != dim:
        raise VtableError(f"{what} is {_article(_NOUN.get(dim, dim))}; {unit!r} is "
                          f"{_article(got)} unit (expected one of "
                          f"{', '.join(units_of(dim))})")


def units_of(dim: str) -> list[str]:
    """Every known unit of one dimension."""
    return [u for u, d in DIMENSIONS.items() if d == dim]


def factor(unit: str) -> float:
    """SI factor of `unit`; an unknown unit is an error naming the known ones."""
    try:
        return UNITS[canonical(unit)]
    except (KeyError, TypeError):
        raise VtableError(f"unknown unit {unit!r}; expected one of {', '.join(UNITS)}") from None


def to_si(value, unit: str):
    """Value in `unit` -> SI (works on scalars and arrays)."""
    return np.asarray(value, dtype=float) * factor(unit) if np.ndim(value) else value * factor(unit)


def from_si(value, unit: str):
    """SI value -> `unit`."""
    return np.asarray(value, dtype=float) / factor(unit) if np.ndim(value) else value / factor(unit)


def weight_to_mass(weight: float, unit: str = "kip") -> float:
    """A weight (force, e.g. kip) -> mass in kg, dividing by standard gravity."""
    return to_si(weight, unit) / G
