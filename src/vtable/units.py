"""The report's units <-> SI, used only at the edges (TOML files, CLI output, runs).

Inside vtable everything is SI: m, kg, s, N, Pa, rad. The report (UCB/EERC-91/13) works
in inches, kips, kip-in-s², psi, in³/s/psi and g; those names are the keys of `UNITS`.
Weights given in kip or lb are forces; `weight_to_mass` turns them into masses.
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

#: factor that converts a value in the named unit to SI
UNITS: dict[str, float] = {
    # length
    "m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": INCH, "ft": FOOT,
    # area, volume
    "m2": 1.0, "in2": INCH**2, "m3": 1.0, "in3": INCH**3,
    # force
    "N": 1.0, "kN": 1e3, "lb": LBF, "kip": KIP,
    # mass
    "kg": 1.0, "lb-s2/in": LBF / INCH, "kip-s2/in": KIP / INCH,
    # rotational inertia
    "kg-m2": 1.0, "kip-in-s2": KIP * INCH, "lb-in-s2": LBF * INCH,
    # pressure
    "Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "psi": PSI,
    # stiffness and damping
    "N/m": 1.0, "kip/in": KIP / INCH, "lb/in": LBF / INCH,
    "N-s/m": 1.0, "lb-s/in": LBF / INCH, "kip-s/in": KIP / INCH,
    "N-m/rad": 1.0, "lb-in/rad": LBF * INCH, "kip-in/rad": KIP * INCH,
    "N-m-s/rad": 1.0, "lb-in-s/rad": LBF * INCH, "kip-in-s/rad": KIP * INCH,
    # moment
    "N-m": 1.0, "kip-ft": KIP * FOOT, "kip-in": KIP * INCH,
    # kinematics
    "m/s": 1.0, "in/s": INCH, "m/s2": 1.0, "in/s2": INCH, "g": G,
    "rad": 1.0, "deg": np.pi / 180, "rad/s": 1.0, "rad/s2": 1.0,
    # hydraulics
    "m3/s": 1.0, "in3/s": INCH**3, "gpm": GALLON / 60,
    "m3/s/Pa": 1.0, "in3/s/psi": INCH**3 / PSI,
    "m2/s": 1.0, "in2/s": INCH**2,  # flow per unit displacement error (k_t)
    "m/Pa": 1.0, "in/psi": INCH / PSI,  # pressure-feedback gain (k_p)
    # time, frequency, dimensionless
    "s": 1.0, "1/s": 1.0, "Hz": 1.0, "1": 1.0, "%": 0.01,
}


def factor(unit: str) -> float:
    """SI factor of `unit`; an unknown unit is an error naming the known ones."""
    try:
        return UNITS[unit]
    except KeyError:
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


def mass_to_weight(mass: float, unit: str = "kip") -> float:
    """A mass in kg -> its weight in `unit` (kip by default)."""
    return from_si(mass * G, unit)
