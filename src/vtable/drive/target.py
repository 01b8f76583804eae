"""The motion a specimen's base should feel (`vtable drive --target`): a CSV of `time` and
`displacement`, or a record processed as `simulate --record` processes it (§9.2)."""

from __future__ import annotations

import csv
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np
import scipy.signal

from vtable import units
from vtable.errors import VtableError
from vtable.signals import make_command

#: the rate the drive is computed and written at (the diagnosis's analysis rate)
DRIVE_FS = 200.0
#: seconds of rest added before and after the target: room for the drive to lead and
#: trail the motion it makes (the inverse of the table's response is not causal)
REST_S = 1.0


@dataclass(frozen=True)
class Target:
    """The target displacement `x` (m) on the uniform grid `t` (s, from 0) at `DRIVE_FS`,
    with `REST_S` of rest before and after the motion given."""

    name: str
    t: np.ndarray
    x: np.ndarray

    @property
    def fs(self) -> float:
        return DRIVE_FS


def read_target(spec: str, unit: str = "in", duration: float | None = None,
                peak: float | None = None) -> Target:
    """A target: `spec` a CSV file with columns `time` (s) and `displacement` (in `unit`),
    or a record as `vtable simulate --record` takes it (elcentro, a .AT2 or .csv of
    acceleration, fema:ID), processed by §9.2 (length scale 3.2801, time scale 1.811) and
    scaled to `peak` (in `unit`; the record's default 4 in when None). Resampled to
    `DRIVE_FS`."""
    p = Path(spec)
    if p.suffix.lower() == ".csv" and _is_displacement_csv(p):
        t, x = _read_csv(p, unit)
        name = p.stem
        if np.ptp(x) == 0:  # nothing to reproduce: every ratio to it would be 0/0 (nan)
            raise VtableError(f"{p}: the target's displacement is constant "
                              f"({units.from_si(x[0], unit):g} {unit} throughout): it does "
                              "not move, there is no drive to compute")
        if peak is not None:  # the motion from where it starts, as the drive plays it
            x = (x - x[0]) * units.to_si(peak, unit) / np.max(np.abs(x - x[0]))
    else:
        peak_in = None if peak is None else units.from_si(units.to_si(peak, unit), "in")
        cmd = make_command("earthquake", record=spec, duration=duration, peak_in=peak_in)
        t, x, name = cmd.t, cmd.x, cmd.name
    return _uniform(name, t, x)


def _is_displacement_csv(p: Path) -> bool:
    try:
        with p.open(newline="") as f:
            header = next(csv.reader(f), [])
    except OSError as e:
        raise VtableError(f"{p}: cannot read the target ({e.strerror})") from None
    return [h.strip() for h in header] == ["time", "displacement"]


def _read_csv(p: Path, unit: str) -> tuple[np.ndarray, np.ndarray]:
    if units.dimension(unit) != "length":
        raise VtableError(f"--target-unit: {unit!r} is not a length unit (m, mm, cm, in, ft)")
    try:
        data = np.loadtxt(p, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as e:
        raise VtableError(f"{p}: not a CSV of numbers under 'time,displacement' ({e})") from None
    if data.shape[1] != 2 or len(data) < 16:
        raise VtableError(f"{p}: expected 2 columns (time, displacement) and at least 16 rows, "
                          f"got {data.shape[1]} columns and {len(data)} rows")
    t, x = data[:, 0], data[:, 1]
    if not np.all(np.isfinite(data)):
        raise VtableError(f"{p}: a value is not a finite number")
    dt = np.diff(t)
    if not np.all(dt > 0) or np.ptp(dt) > 1e-6 * np.mean(dt) + 1e-9:
        raise VtableError(f"{p}: 'time' must increase in uniform steps")
    return t - t[0], units.to_si(x, unit)


def _uniform(name: str, t: np.ndarray, x: np.ndarray) -> Target:
    """Resample to DRIVE_FS (polyphase, anti-aliased)."""
    fs = 1.0 / float(np.mean(np.diff(t)))
    if abs(fs - DRIVE_FS) > 1e-6 * DRIVE_FS:
        r = Fraction(DRIVE_FS / fs).limit_denominator(1000)
        x = scipy.signal.resample_poly(x, r.numerator, r.denominator)
    rest = np.zeros(round(REST_S * DRIVE_FS))
    x = np.concatenate([rest, np.asarray(x, dtype=float) - x[0], rest + (x[-1] - x[0])])
    return Target(name, np.arange(len(x)) / DRIVE_FS, x)
