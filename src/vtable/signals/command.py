"""A command for the table: a horizontal displacement history made from a signal or an
earthquake record (§3.2 random, sine, pulse, §9.2 processed earthquake), with its run-format
[command] table."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from vtable import units
from vtable.errors import VtableError
from vtable.signals.basic import band_limited_random, pulse, sine
from vtable.signals.processing import REST_SECONDS, first_seconds, process_record
from vtable.signals.records import load_record

COMMAND_DT = 0.001


@dataclass(frozen=True)
class Command:
    """A horizontal displacement command (SI), its run-format [command] table, and notes
    on how it was made (what a user should know: scaling, truncation)."""

    name: str
    t: np.ndarray
    x: np.ndarray
    table: dict[str, Any]
    notes: tuple[str, ...] = ()


#: default length of the generated commands (s); an earthquake plays its whole record
DEFAULT_DURATION = 11.0


#: the length units a command may describe itself in (its [command] key peak_<unit>)
COMMAND_UNITS = ("in", "mm", "m")


def make_command(kind: str = "random", *, duration: float | None = None,
                 band: tuple[float, float] = (0.0, 25.0), peak_in: float | None = None,
                 frequency: float = 2.0, seed: int = 0, record: str | None = None,
                 length_scale: float = 3.2801, unit: str = "in") -> Command:
    """random (band-limited, §3.2), sine, pulse or earthquake (§9.2 processing of the
    record named as `load_record` takes it: elcentro, a .AT2 or .csv file, fema:ID);
    `peak_in` is the peak displacement. `duration` (s) defaults to 11 s, and for an
    earthquake to the whole record; a shorter one takes the processed record's first
    seconds as the whole record plays them (scaled so that the whole reaches `peak_in`),
    brought to rest over its last seconds (`first_seconds`). `unit` (in, mm or m) is the
    one the command's notes and its [command] table's peak (peak_<unit>) are in."""
    if duration is not None and not (np.isfinite(duration) and duration > 0):
        raise VtableError(f"duration must be a positive number of seconds, got {duration!r}")
    if unit not in COMMAND_UNITS:
        raise VtableError(f"a command's unit is one of {', '.join(COMMAND_UNITS)}, got "
                          f"{unit!r}")
    key = f"peak_{unit}"
    if kind == "random":
        peak = units.to_si(peak_in if peak_in is not None else 0.25, "in")
        t, x = band_limited_random(duration or DEFAULT_DURATION, COMMAND_DT, band, peak=peak,
                                   seed=seed)
        return Command(f"random {band[0]:g}-{band[1]:g} Hz", t, x,
                       {"kind": "random", "band_hz": list(band),
                        key: float(units.from_si(peak, unit)), "seed": seed})
    if kind == "sine":
        amp = units.to_si(peak_in if peak_in is not None else 0.1, "in")
        d = duration or DEFAULT_DURATION
        t, x = sine(d, COMMAND_DT, frequency, amp, ramp=min(1.0, d / 4))
        return Command(f"sine {frequency:g} Hz", t, x,
                       {"kind": "sine", "frequency_hz": frequency,
                        key: float(units.from_si(amp, unit))})
    if kind == "pulse":
        amp = units.to_si(peak_in if peak_in is not None else 1.0, "in")
        t, x = pulse(duration or DEFAULT_DURATION, COMMAND_DT, width=1.0, amplitude=amp,
                     start=0.5)
        return Command("pulse", t, x,
                       {"kind": "pulse", key: float(units.from_si(amp, unit))})
    if kind == "earthquake":
        return _earthquake(record, duration, peak_in, length_scale, unit)
    raise VtableError(f"unknown command kind {kind!r}; expected random, sine, pulse or "
                      "earthquake")


def _earthquake(record: str | None, duration: float | None, peak_in: float | None,
                length_scale: float, unit: str) -> Command:
    """The §9.2-processed record scaled to `peak_in`, or its first `duration` seconds as
    the whole plays them (`first_seconds`); its notes in `unit`."""
    rec = load_record(record)
    peak = units.to_si(peak_in if peak_in is not None else 4.0, "in")
    time_scale = float(np.sqrt(length_scale))
    notes = list(getattr(rec, "notes", ()))
    full = rec.duration / time_scale
    if duration is not None and duration > full * (1 + 1e-9):
        raise VtableError(f"--duration {duration:g} s is longer than the processed record "
                          f"{rec.name} ({full:.2f} s after the time scale {time_scale:.4g})")
    cmd = process_record(rec, length_scale=length_scale, peak_displacement=peak)

    def shown(x_m: float) -> str:
        return f"{units.from_si(x_m, unit):.3g} {unit}"

    notes.append(f"§9.2 processing: length scale {length_scale:g}, time scale "
                 f"{time_scale:.4g}, integrated with zero end conditions, scaled to "
                 f"±{shown(peak)} peak"
                 + ("" if peak_in is not None else " (the default; --peak sets it)"))
    if duration is not None and duration < full * (1 - 1e-9):
        if duration < 3 * cmd.dt:
            raise VtableError(f"--duration {duration:g} s is shorter than three steps of the "
                              f"processed record {rec.name} ({cmd.dt:.4g} s each)")
        cmd = first_seconds(cmd, duration)
        rest = min(REST_SECONDS, cmd.time[-1] / 3)
        notes.append(f"first {duration:g} s of the processed record (record time 0-"
                     f"{cmd.time[-1] * time_scale:.2f} s), scaled as the whole record is "
                     f"(the whole reaches ±{shown(peak)}, this part's own "
                     f"{shown(float(np.max(np.abs(cmd.displacement))))}); its last "
                     f"{rest:.2g} s bring the table to rest")
    t_new = np.arange(0.0, cmd.time[-1] + 1e-12, COMMAND_DT)
    x = np.interp(t_new, cmd.time, cmd.displacement)
    table = {"kind": "earthquake", "record": rec.name, "length_scale": length_scale,
             "time_scale": time_scale, f"peak_{unit}": float(units.from_si(peak, unit))}
    return Command(f"{rec.name}", t_new, x, table, tuple(notes))
