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
from vtable.signals.processing import process_record
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


def make_command(kind: str = "random", *, duration: float | None = None,
                 band: tuple[float, float] = (0.0, 25.0), peak_in: float | None = None,
                 frequency: float = 2.0, seed: int = 0, record: str | None = None,
                 length_scale: float = 3.2801) -> Command:
    """random (band-limited, §3.2), sine, pulse or earthquake (§9.2 processing of the
    record named as `load_record` takes it: elcentro, a .AT2 or .csv file, fema:ID);
    `peak_in` is the peak displacement. `duration` (s) defaults to 11 s, and for an
    earthquake to the whole record; a shorter one takes the record's beginning (cut before
    the §9.2 integration, so the command still starts and ends at rest)."""
    if duration is not None and not (np.isfinite(duration) and duration > 0):
        raise VtableError(f"duration must be a positive number of seconds, got {duration!r}")
    if kind == "random":
        peak = units.to_si(peak_in if peak_in is not None else 0.25, "in")
        t, x = band_limited_random(duration or DEFAULT_DURATION, COMMAND_DT, band, peak=peak,
                                   seed=seed)
        return Command(f"random {band[0]:g}-{band[1]:g} Hz", t, x,
                       {"kind": "random", "band_hz": list(band), "peak_in": units.from_si(
                           peak, "in"), "seed": seed})
    if kind == "sine":
        amp = units.to_si(peak_in if peak_in is not None else 0.1, "in")
        d = duration or DEFAULT_DURATION
        t, x = sine(d, COMMAND_DT, frequency, amp, ramp=min(1.0, d / 4))
        return Command(f"sine {frequency:g} Hz", t, x,
                       {"kind": "sine", "frequency_hz": frequency,
                        "peak_in": units.from_si(amp, "in")})
    if kind == "pulse":
        amp = units.to_si(peak_in if peak_in is not None else 1.0, "in")
        t, x = pulse(duration or DEFAULT_DURATION, COMMAND_DT, width=1.0, amplitude=amp,
                     start=0.5)
        return Command("pulse", t, x, {"kind": "pulse", "peak_in": units.from_si(amp, "in")})
    if kind == "earthquake":
        return _earthquake(record, duration, peak_in, length_scale)
    raise VtableError(f"unknown command kind {kind!r}; expected random, sine, pulse or "
                      "earthquake")


def _earthquake(record: str | None, duration: float | None, peak_in: float | None,
                length_scale: float) -> Command:
    rec = load_record(record)
    peak = units.to_si(peak_in if peak_in is not None else 4.0, "in")
    time_scale = float(np.sqrt(length_scale))
    notes = list(getattr(rec, "notes", ()))
    window = None
    full = rec.duration / time_scale
    if duration is not None:
        if duration > full * (1 + 1e-9):
            raise VtableError(f"--duration {duration:g} s is longer than the processed record "
                              f"{rec.name} ({full:.2f} s after the time scale "
                              f"{time_scale:.4g})")
        window = (0.0, min(duration * time_scale, rec.duration))
    cmd = process_record(rec, length_scale=length_scale, peak_displacement=peak, window=window,
                         scale_as_whole=True)
    notes.append(f"§9.2 processing: length scale {length_scale:g}, time scale "
                 f"{time_scale:.4g}, integrated with zero end conditions, scaled to "
                 f"±{units.from_si(peak, 'in'):g} in peak"
                 + ("" if peak_in is not None else " (the default; --peak sets it)"))
    if window is not None:
        own = units.from_si(float(np.max(np.abs(cmd.displacement))), "in")
        notes.append(f"first {duration:g} s of the processed record (record time 0-"
                     f"{window[1]:.2f} s), scaled as the whole record is: the whole "
                     f"record's peak is the ±{units.from_si(peak, 'in'):g} in, this "
                     f"part's own {own:.3g} in")
    t_new = np.arange(0.0, cmd.time[-1] + 1e-12, COMMAND_DT)
    x = np.interp(t_new, cmd.time, cmd.displacement)
    table = {"kind": "earthquake", "record": rec.name, "length_scale": length_scale,
             "time_scale": time_scale, "peak_in": units.from_si(peak, "in")}
    return Command(f"{rec.name}", t_new, x, table, tuple(notes))
