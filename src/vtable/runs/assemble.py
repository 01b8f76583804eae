"""A run from its checked metadata and raw columns (file units), whichever file they
came from: the time base, units to SI, plausible magnitudes, the reader's reports, the
checks that need the sampling rate, and the command from a drive file.

Things the format allows but a user should know about — unknown channels (kept),
missing samples (kept as NaN, counted per channel), constant channels, time stamps put
on a uniform grid — are collected in `Run.reports`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from vtable import units as un
from vtable.errors import VtableError
from vtable.runs.channels import COMMAND_CHANNELS, FORMAT_UNITS
from vtable.runs.drive import apply_drive
from vtable.runs.meta import Declaration, check_against_rate
from vtable.runs.model import Run
from vtable.runs.timebase import check_time


def locate(first_line: int, what: str) -> Callable[[int], str]:
    """Sample index -> "line 7" (CSV, header on line 1) or "sample 5" (HDF5)."""
    return lambda i: f"{what} {i + first_line}"


def _check_channel(name: str, v: np.ndarray, unit: str, where: Path | str,
                   at: Callable[[int], str]) -> None:
    """Values (in `unit`, before conversion) of plausible magnitude for the channel's
    dimension (`units.PLAUSIBLE_MAX`); finite or NaN."""
    dim = un.dimension(unit)
    limit = un.from_si(un.PLAUSIBLE_MAX[dim], unit)
    a = np.abs(v)
    peak = np.fmax.reduce(a) if len(a) else 0.0
    if peak > limit:  # False for NaN
        i = int(np.flatnonzero(a > limit)[0])
        raise VtableError(f"{where}: {at(i)}, column {name!r}: {v[i]:.6g} {unit} is not a "
                          f"plausible {un.noun(dim)} (the limit is {limit:.3g} {unit})")


def _channel_reports(name: str, v: np.ndarray, unit: str, where: Path | str,
                     at: Callable[[int], str]) -> list[str]:
    out = []
    nan = np.isnan(v)
    n = int(nan.sum())
    if n == len(v):
        return [f"{where}: column {name!r} has no samples (all {n} missing samples)"]
    if n:
        out.append(f"{where}: column {name!r} has {n} missing samples of {len(v)} (first at "
                   f"{at(int(np.argmax(nan)))}); kept as NaN, not filled: what needs this "
                   "channel refuses it")
    lo, hi = np.fmin.reduce(v), np.fmax.reduce(v)
    if lo == hi:
        role = "it drives nothing" if name in COMMAND_CHANNELS else "it carries no signal"
        out.append(f"{where}: column {name!r} is constant ({un.from_si(lo, unit):g} {unit}): "
                   f"{role}")
    return out


#: Hz: the range of a lab acquisition's sampling rate; a declared time unit that puts a
#: run outside it, when seconds would not, is asked about (`_time_unit_hint`)
LAB_RATES_HZ = (50.0, 20000.0)


def _time_unit_hint(time: np.ndarray, unit: str, where: str) -> list[str]:
    """A note asking whether 'time' is really in `unit` ([units] time), when that unit
    puts the sampling rate outside `LAB_RATES_HZ` and seconds would put it inside."""
    if len(time) < 2 or not time[-1] > time[0]:
        return []
    fs = (len(time) - 1) / (time[-1] - time[0])
    fs_s = fs * un.factor(unit)  # the rate if the stamps were seconds
    lo, hi = LAB_RATES_HZ
    if lo <= fs <= hi or not lo <= fs_s <= hi:
        return []
    return [f"{where}: [units] time = {unit!r} makes the run sampled at {fs:.6g} Hz; its "
            f"stamps read in seconds would be {fs_s:.6g} Hz: is 'time' in {unit}? (taken "
            "as declared)"]


def assemble(name: str, header: list[str], data: np.ndarray, decl: Declaration,
             reports: list[str], toml_where: str, data_where: Path | str, source: Path,
             first_line: int, what: str, file_units: dict[str, str] | None = None) -> Run:
    """Run from checked metadata and raw columns (file units): time base, units to SI,
    plausibility, reports, the checks that need the sampling rate, the command from a
    drive file (`vtable.runs.drive.apply_drive`). `file_units` are the columns' units
    when the file names them all (HDF5); else the [units] overrides of `decl`."""
    at = locate(first_line, what)
    overrides = decl.units if file_units is None else file_units
    t_unit = overrides.get("time", "s")
    _check_channel("time", data[0], t_unit, data_where, at)
    t = data[0] * un.factor(t_unit) if t_unit != "s" else data[0]
    time, dev = check_time(t, data_where, first_line, what)
    if time is not t:
        dt = (time[-1] - time[0]) / (len(time) - 1)
        reports.append(f"{data_where}: time stamps deviate from a uniform grid by up to "
                       f"{dev:.3g} s ({dev / dt:.3%} of the {dt:.9g} s step); the uniform "
                       "grid t0 + k·dt is used")
    elif t_unit != "s":
        time = t.copy()
    if t_unit != "s":
        reports += _time_unit_hint(time, t_unit, toml_where)
    channels, units, extra = {}, {}, []
    for j, h in enumerate(header[1:], start=1):
        unit = overrides.get(h, FORMAT_UNITS.get(h))
        if h not in FORMAT_UNITS:
            extra.append(h)
        units[h] = unit or "1"
        v = data[j]
        _check_channel(h, v, units[h], data_where, at)
        f = un.factor(units[h])
        if f != 1.0:
            v *= f  # in place: the array is the reader's own
        channels[h] = v
        reports += _channel_reports(h, v, units[h], data_where, at)
    if extra:
        no_unit = [h for h in extra if h not in overrides]
        reports.append(f"{data_where}: {len(extra)} column(s) not in the format, kept: "
                       + ", ".join(extra[:6]) + (", ..." if len(extra) > 6 else "")
                       + (f" ({len(no_unit)} without a unit)" if no_unit else ""))
    for h in overrides:
        if h not in channels and h != "time":
            reports.append(f"{toml_where}: [units] names {h!r}, which is not a column (kept, "
                           "not used)")
    if "h_span" not in channels and decl.drive_file is None:
        reports.append(f"{toml_where}: no h_span column and no [command] drive_file: the "
                       "command the table played is not known")
    check_against_rate(decl, (len(time) - 1) / (time[-1] - time[0]), toml_where)
    missing = {h: int(np.isnan(v).sum()) for h, v in channels.items()}
    run = Run(name=name, time=time, channels=channels, units=units, meta=decl.meta,
              source=source, missing={h: n for h, n in missing.items() if n}, extra=extra,
              reports=reports, declared=decl)
    if decl.drive_file is not None:
        run = apply_drive(run, toml_where)  # the command from the drive file
    return run
