"""The units vtable shows a run's quantities in: the report's (in, mil, g, kip) for a run
or table declared in inches, pounds or kips; metric (mm, m/s², kN, kg) for one declared in
metres, newtons or kilograms. Values stay SI inside; this is only the last step of a
report line."""

from __future__ import annotations

from collections.abc import Iterable

from vtable import units

#: the report unit of a displayed quantity -> its metric counterpart
METRIC = {"in": "mm", "g": "m/s2", "kip": "kN", "lb": "N", "in/s": "mm/s", "in/s2": "m/s2",
          "psi": "MPa", "kip-in": "kN-m"}
_IMPERIAL = {"in", "ft", "lb", "kip", "psi", "in/s", "in/s2", "g", "kip-in", "kip-ft"}
_METRIC = {"m", "mm", "cm", "N", "kN", "kg", "Pa", "kPa", "MPa", "m/s", "mm/s", "cm/s",
           "m/s2", "mm/s2", "cm/s2", "N-m"}


def family(declared: Iterable[str]) -> str:
    """'metric' when the declared units (a run's [units] values, a table's keys' units)
    hold a metric length, force or mass and no imperial one; 'imperial' otherwise (the
    report's units, the default)."""
    found = set(declared)
    return "metric" if found & _METRIC and not found & _IMPERIAL else "imperial"


def run_family(run) -> str:
    """The unit family of a run's declared [units] (its length channels decide first)."""
    length = [u for u in run.units.values() if units.DIMENSIONS.get(u) == "length"]
    return family(length or run.units.values())


def shown(value_si: float, report_unit: str, fam: str) -> tuple[float, str]:
    """A value (SI) in the unit it is shown in: `report_unit` for an imperial run, its
    metric counterpart (`METRIC`) for a metric one."""
    unit = METRIC.get(report_unit, report_unit) if fam == "metric" else report_unit
    return units.from_si(value_si, unit), unit


def amplitude(x_m: float, fam: str = "imperial") -> str:
    """A command amplitude in metres as '30 mil' (imperial; 1 mil = 0.001 in) or
    '0.76 mm' (metric)."""
    if fam == "metric":
        v = 1000 * x_m
        return f"{v:.3g} mm"
    v = 1000 * units.from_si(x_m, "in")
    return (f"{v:.0f}" if v >= 10 else f"{v:.2g}") + " mil"
