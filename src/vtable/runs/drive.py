"""The command as the drive file the controller played ([command] drive_file, drive_unit,
drive_scale, drive_offset_s; docs/run-format.md).

Many acquisitions record only the responses: the command x_c is the drive file, scaled by
the operator's span factor and offset in time by the samples the acquisition lost. With
drive_offset_s = o (s, the drive leads the acquisition), the command at acquisition time t
is

    x_c(t) = drive_scale · unit · d(t + o),

d interpolated (a cubic spline, exact at the drive's own samples) onto the run's time
grid; a drive sampled faster than the run is first low-passed at 0.45 fs of the run
(zero-phase Butterworth, so no lag is added). Outside the drive's span the command is
held at the drive's first or last value (the table at rest) and the samples are counted
in the report line.

drive_offset_s = "auto": the offset is not known until the table's response is
identified (the table delays its response, so the lag of x_t behind the drive is not the
offset). The reader leaves the command out and says so in a report line;
`vtable.ident.drive.align` estimates the offset and makes the command with `with_command`.

A run with both an h_span column and a drive file: the column wins (it is what the
controller recorded) and the drive is checked against it: the lag and the scale that best
map the drive onto the column are reported, with a warning when they disagree with
drive_offset_s or drive_scale by more than a sample or 1 %.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.interpolate
import scipy.signal

from vtable import units as un
from vtable.errors import VtableError
from vtable.runs.model import Run

#: the drive is low-passed at this fraction of the run's sampling rate when sampled faster
LOWPASS = 0.45
#: a drive/column disagreement worth a warning: scale ratio off by more than this
SCALE_TOL = 0.01


@dataclass(frozen=True)
class DriveFile:
    """A drive file's samples: time (s, strictly increasing) and displacement (m, the
    file's values x unit x drive_scale)."""

    path: Path
    t: np.ndarray
    x: np.ndarray
    unit: str
    scale: float

    @property
    def dt(self) -> float:
        return float(np.median(np.diff(self.t)))


def read_drive(path: Path, unit: str | None, scale: float | None, where: str) -> DriveFile:
    """The two-column CSV (time, displacement; an optional header line), in SI and
    scaled. Errors are one line naming the file and `where` (the drive_file key)."""
    key = f"({where}.drive_file)"
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise VtableError(f"{path}: no such file {key}") from None
    except (OSError, UnicodeDecodeError) as e:
        raise VtableError(f"{path}: cannot read the drive file {key}: "
                          f"{getattr(e, 'strerror', None) or type(e).__name__}") from None
    lines = text.splitlines()
    first = 0
    if lines and not _numeric(lines[0]):
        first = 1  # a header
    rows = []
    for i, ln in enumerate(lines[first:], start=first + 1):
        if not ln.strip():
            continue
        cells = ln.split(",")
        if len(cells) != 2:
            raise VtableError(f"{path}: line {i} has {len(cells)} fields; a drive file has two "
                              f"columns, time and displacement {key}")
        try:
            a, b = float(cells[0]), float(cells[1])
        except ValueError:
            raise VtableError(f"{path}: line {i}: {ln.strip()[:40]!r} is not two numbers "
                              f"{key}") from None
        if not (math.isfinite(a) and math.isfinite(b)):
            raise VtableError(f"{path}: line {i}: not finite {key}")
        rows.append((a, b))
    if len(rows) < 2:
        raise VtableError(f"{path}: needs at least two samples, got {len(rows)} {key}")
    d = np.array(rows)
    steps = np.diff(d[:, 0])
    if not np.all(steps > 0):
        i = int(np.argmax(steps <= 0)) + first + 2
        raise VtableError(f"{path}: the time column is not increasing at line {i} {key}")
    u = unit or "in"
    x = d[:, 1] * un.factor(u) * (scale if scale is not None else 1.0)
    return DriveFile(path, d[:, 0], x, u, scale if scale is not None else 1.0)


def _numeric(line: str) -> bool:
    try:
        [float(c) for c in line.split(",")]
    except ValueError:
        return False
    return True


def on_grid(drive: DriveFile, t: np.ndarray, offset: float) -> tuple[np.ndarray, int]:
    """x_c(t) = d(t + offset) on the run's grid `t`, and the number of samples outside the
    drive's span (held at its end values). Band-limited first when the drive is sampled
    faster than the run (module docstring)."""
    dt = float((t[-1] - t[0]) / (len(t) - 1))
    x = drive.x
    if drive.dt < dt * (1 - 1e-3) and len(x) > 30:
        sos = scipy.signal.butter(8, LOWPASS / dt, fs=1 / drive.dt, output="sos")
        x = scipy.signal.sosfiltfilt(sos, x)
    tq = t + offset
    spline = scipy.interpolate.CubicSpline(drive.t, x)
    out = spline(np.clip(tq, drive.t[0], drive.t[-1]))
    outside = int(np.sum((tq < drive.t[0] - 1e-9 * dt) | (tq > drive.t[-1] + 1e-9 * dt)))
    return out, outside


def coarse_offset(drive: DriveFile, t: np.ndarray, y: np.ndarray) -> float:
    """o₀: the drive resampled on the run's step from its start, its lag at the peak of
    the cross-correlation with the response y (positive peak: scale > 0)."""
    dt = float((t[-1] - t[0]) / (len(t) - 1))
    tg = drive.t[0] + dt * np.arange(int(np.floor((drive.t[-1] - drive.t[0]) / dt)) + 1)
    g, _ = on_grid(drive, tg, 0.0)
    c = scipy.signal.correlate(g - g.mean(), y - y.mean(), mode="full", method="fft")
    lags = scipy.signal.correlation_lags(len(g), len(y), mode="full")
    lag = int(lags[int(np.argmax(c))])
    return float(drive.t[0] + lag * dt - t[0])


def _check_column(run: Run, drive: DriveFile, offset: float) -> str:
    """The h_span column against the drive: the lag (samples, beyond `offset`) and scale
    that map the drive onto the column best."""
    col = run.channels["h_span"]
    coarse = coarse_offset(drive, run.time, col)
    x, _ = on_grid(drive, run.time, coarse)
    ok = np.isfinite(col)
    ratio = float(np.dot(x[ok], col[ok]) / np.dot(x[ok], x[ok])) if np.any(x[ok]) else math.nan
    lag = (coarse - offset) * run.fs
    warn = abs(lag) > 1 or not abs(ratio - 1) <= SCALE_TOL
    return (f"the h_span column is the command; the drive file {drive.path.name} checked "
            f"against it: lag {lag:+.0f} samples beyond drive_offset_s, column/drive scale "
            f"{ratio:.4g}" + (" ⚠ they disagree" if warn else " (they agree)"))


#: the report line of a run whose command h_span the reader made from its drive file
#: begins so (after the run's name)
FROM_DRIVE = "command h_span from the drive file"
#: the report line a run with drive_offset_s = "auto" carries until it is aligned
AUTO_PENDING = ("command h_span not made: drive_offset_s = \"auto\" is estimated from the "
                "table's response when the run is aligned (vtable.ident.drive.align)")


def apply_drive(run: Run, where: str) -> Run:
    """The run with its command h_span made from the drive file at the given
    drive_offset_s (or, with an h_span column, the drive checked against it), and a
    report line naming the file, the scale and the offset. With drive_offset_s = "auto"
    the run is returned with the report line `AUTO_PENDING` (`vtable.ident.drive.align`
    makes the command). `where` names the TOML."""
    cmd = run.drive()
    if cmd is None or cmd.drive_file is None:
        return run
    key = f"{where} [command]"
    drive = read_drive(cmd.drive_file, cmd.drive_unit, cmd.drive_scale, key)
    if run.has("h_span"):
        off = 0.0 if cmd.drive_offset in (None, "auto") else float(cmd.drive_offset)
        line = f"{where}: {_check_column(run, drive, off)}"
        return dataclasses.replace(run, reports=[*run.reports, line])
    if cmd.drive_offset == "auto":
        return dataclasses.replace(run, reports=[*run.reports, f"{where}: {AUTO_PENDING}"])
    offset = float(cmd.drive_offset or 0.0)
    return with_command(run, drive, offset, f"offset {offset:g} s ({offset * run.fs:.4g} "
                        "samples, given)", where)


def with_command(run: Run, drive: DriveFile, offset: float, how: str, where: str) -> Run:
    """The run with h_span = the drive at `offset` (s) on its time grid, and the report
    line naming the file, the scale and `how` the offset was found."""
    name = drive.path.name
    key = f"{where} [command]"
    t = run.time
    if not (t[0] + offset < drive.t[-1] and t[-1] + offset > drive.t[0]):
        raise VtableError(f"{key}.drive_offset_s: {offset:g} s puts the drive {name} "
                          f"({drive.t[0]:g}-{drive.t[-1]:g} s) outside the run "
                          f"({t[0]:g}-{t[-1]:g} s)")
    x, outside = on_grid(drive, t, offset)
    faster = " (low-passed at 0.45 fs)" if drive.dt < run.dt * (1 - 1e-3) else ""
    line = (f"{where}: {FROM_DRIVE} {name} ({drive.unit}, scale "
            f"{drive.scale:g}{faster}), {how}")
    if outside:
        line += (f"; {outside} samples outside the drive's span are held at its end "
                 "values")
    channels = {"h_span": x, **run.channels}
    units = {"h_span": "in", **run.units}
    return dataclasses.replace(run, channels=channels, units=units,
                               reports=[*run.reports, line])
