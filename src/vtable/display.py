"""The units vtable shows and writes a run's quantities in — the one place that chooses
them. Two families: the report's (in, mil, g, kip) for a run or table declared in inches,
pounds or kips; metric (mm, m/s², kN, kg) for one declared in metres, newtons or
kilograms. Values stay SI inside (and in every JSON); this is only the last step of a
printed line and the unit a run file holds its channels in.

A simulated run on a metric table is written in mm, mm/s, g and kN (`file_units`): the
accelerometers in g, as LNEC, the metric lab whose runs vtable reads, declares them. A
run's printed channel values follow its own [units] (a run declaring g is shown in g, one
declaring m/s² in m/s²); a quantity no channel declares follows the family (`METRIC`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from vtable import units

#: the report unit of a displayed quantity -> its metric counterpart
METRIC = {"in": "mm", "mil": "mm", "g": "m/s2", "kip": "kN", "lb": "N", "in/s": "mm/s",
          "in/s2": "m/s2", "psi": "MPa", "kip-in": "kN-m", "kip-ft": "kN-m",
          "kip/in": "kN/mm", "lb/in": "kN/m", "lb-s/in": "kN-s/m", "kip-s/in": "kN-s/m",
          "lb-in/rad": "kN-m/rad", "kip-in/rad": "kN-m/rad", "lb-in-s/rad": "kN-m-s/rad",
          "kip-in-s/rad": "kN-m-s/rad", "1/in": "1/mm", "kip-in-s2": "kg-m2",
          "lb-in-s2": "kg-m2"}
#: the format's channel units (in, in/s, g, kip) -> the unit a metric run file holds them
#: in: mm, mm/s, kN, and g (LNEC's accelerometers, as its runs declare them)
METRIC_FILE = {"in": "mm", "in/s": "mm/s", "kip": "kN", "g": "g"}
#: display-only units (not accepted in files): SI factor of each
_SHOWN_ONLY = {"mil": units.to_si(1e-3, "in"), "kN/mm": 1e6, "kN/m": 1e3, "kN-s/m": 1e3,
               "kN-m/rad": 1e3, "kN-m-s/rad": 1e3, "1/mm": 1e3}
#: g is neither: the report's accelerations and a metric lab's (LNEC's) are both in g
_IMPERIAL = {"in", "ft", "lb", "kip", "psi", "in/s", "in/s2", "kip-in", "kip-ft"}
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


def table_family(lab) -> str:
    """The units a table's runs are written and shown in: the report's for the EERC
    table, metric for a table described in SI (the presets other than eerc, a table
    file in the run format's SI keys)."""
    return "imperial" if lab.name == "eerc" else "metric"


def file_units(channel_units: Mapping[str, str], fam: str) -> dict[str, str]:
    """Each channel's unit in a run file of family `fam`: the format's own (in, g, kip)
    for an imperial run; for a metric one `METRIC_FILE` (mm, mm/s, g, kN), other units
    (SI states, rad) kept."""
    if fam != "metric":
        return dict(channel_units)
    return {k: METRIC_FILE.get(u, u) for k, u in channel_units.items()}


def from_si(value_si, unit: str):
    """An SI value in `unit`: any unit of `vtable.units`, or a display-only one (mil,
    kN/mm, kN-s/m, kN-m/rad, kN-m-s/rad, 1/mm)."""
    if unit in _SHOWN_ONLY:
        return value_si / _SHOWN_ONLY[unit]
    return units.from_si(value_si, unit)


def unit_for(report_unit: str, fam: str, declared: Iterable[str] = ()) -> str:
    """The unit a quantity the report gives in `report_unit` is shown in: the same for an
    imperial run; for a metric one its metric counterpart, or, when the run declares a
    unit of that quantity's dimension (`declared`, e.g. its [units] values), that one."""
    if fam != "metric":
        return report_unit
    dim = units.DIMENSIONS.get(report_unit)
    if dim is not None:
        own = [u for u in declared if units.DIMENSIONS.get(u) == dim]
        if own:
            return own[0]
    return METRIC.get(report_unit, report_unit)


def shown(value_si: float, report_unit: str, fam: str,
          declared: Iterable[str] = ()) -> tuple[float, str]:
    """A value (SI) in the unit it is shown in (`unit_for`) and that unit."""
    unit = unit_for(report_unit, fam, declared)
    return from_si(value_si, unit), unit


def quantity(value_si: float, report_unit: str, fam: str, spec: str = ".3g",
             declared: Iterable[str] = ()) -> str:
    """A value (SI) as the user reads it: '2.98 kip' (imperial) or '13.3 kN' (metric);
    `spec` the number's format."""
    value, unit = shown(value_si, report_unit, fam, declared)
    return f"{value:{spec}}" + ("" if unit == "1" else f" {label(unit)}")


def label(unit: str) -> str:
    """A unit as printed: m/s² for m/s2, kg·m² for kg-m2; others as named."""
    return unit.replace("s2", "s²").replace("m2", "m²") if unit.endswith("2") else unit


def amplitude(x_m: float, fam: str = "imperial") -> str:
    """A command amplitude in metres as '30 mil' (imperial; 1 mil = 0.001 in) or
    '0.76 mm' (metric)."""
    if fam == "metric":
        return f"{from_si(x_m, 'mm'):.3g} mm"
    v = from_si(x_m, "mil")
    return (f"{v:.0f}" if v >= 10 else f"{v:.2g}") + " mil"
