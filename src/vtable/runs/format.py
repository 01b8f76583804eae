"""Runs in the interchange format (docs/run-format.md, version 1):
RUN.csv (time + channels) and RUN.toml (what was tested)."""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vtable import units
from vtable.analytic.structure import building_matrices, fixed_base_modes
from vtable.errors import VtableError, did_you_mean
from vtable.params.base import check_number
from vtable.params.specimen import OPENSEES_DATA_KEYS
from vtable.params.table import DIRECTIONS, KNOBS

FORMAT = "vtable-run/1"
SPECIMEN_KEYS = {"none": (), "rigid": ("weight_kip", "height_in"),
                 "sdof": ("weight_kip", "height_in", "frequency_hz", "damping", "hysteresis"),
                 "shear_building": ("weights_kip", "heights_in", "frequencies_hz", "damping",
                                    "damping_rayleigh", "hysteresis"),
                 "opensees": ("model",)}


def specimen_table(spec) -> dict[str, Any]:
    """A specimen's [specimen] table with exactly the run format's keys."""
    d = spec.to_dict()
    kind = d["kind"]
    out: dict[str, Any] = {"kind": kind}
    for k in SPECIMEN_KEYS[kind]:
        if k in d:
            out[k] = d[k]
    if kind == "shear_building" and "frequencies_hz" not in d:
        M, K, _ = building_matrices(spec)
        w, _ = fixed_base_modes(M, K)
        out["frequencies_hz"] = (w / (2 * np.pi)).tolist()
    if kind == "opensees" and spec.building is not None:  # the model as data
        b = specimen_table(spec.building)
        out.update({k: b[k] for k in OPENSEES_DATA_KEYS})
    return out


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string is a valid TOML basic string
    if isinstance(v, int | float | np.floating | np.integer):
        return repr(float(v)) if isinstance(v, float | np.floating) else str(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(x)}" for k, x in v.items()) \
            + " }"
    raise VtableError(f"a run's metadata cannot hold a {type(v).__name__} ({v!r:.40})")


def _toml_key(k: str) -> str:
    """A bare key when TOML allows one, else a quoted key."""
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)


def dumps_toml(d: dict[str, Any]) -> str:
    """Minimal TOML writer for run metadata (top-level scalars, then tables)."""
    lines = [f"{_toml_key(k)} = {_toml_value(v)}" for k, v in d.items()
             if not isinstance(v, dict)]
    for k, v in d.items():
        if isinstance(v, dict):
            lines.append(f"\n[{_toml_key(k)}]")
            lines += [f"{_toml_key(kk)} = {_toml_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


# ---- [control] ------------------------------------------------------------------------
def check_control(d: Any, where: str) -> list[str]:
    """Check a [control] table (report Table 3.2 knob positions per direction): every knob
    a finite number >= 0; unknown directions and knobs are returned as notes."""
    notes: list[str] = []
    for direction, knobs in d.items():
        w = f"{where[:-1]}.{direction}]" if where.endswith("]") else f"{where}.{direction}"
        if direction not in DIRECTIONS:
            notes.append(f"{where}: unknown direction {direction!r} (kept, not used; "
                         f"expected {', '.join(DIRECTIONS)})")
            continue
        if not isinstance(knobs, dict):
            raise VtableError(f"{w}: expected a table of knobs {', '.join(KNOBS)}, got "
                              f"{type(knobs).__name__}")
        for knob, v in knobs.items():
            if knob not in KNOBS:
                notes.append(f"{w}: unknown knob {knob!r} (kept, not used; expected "
                             f"{', '.join(KNOBS)})")
                continue
            if check_number(v, f"{w}.{knob}") < 0:
                raise VtableError(f"{w}.{knob}: a knob position is >= 0, got {v!r}")
    return notes


# ---- [command] ------------------------------------------------------------------------
COMMAND_KINDS = ("random", "sine", "pulse", "earthquake")
#: [command] keys of the format, and those vtable writes for its own commands
COMMAND_KEYS = ("kind", "band_hz", "span", "drive_file", "drive_unit", "drive_scale",
                "drive_offset_s", "peak_in", "peak_mm", "peak_m", "seed", "frequency_hz",
                "record", "length_scale", "lead_s",
                "time_scale")


@dataclass(frozen=True)
class CommandDescription:
    """What a run's [command] says (SI): the command's kind and band, and the drive file
    the controller played when the run has no h_span column."""

    kind: str | None = None
    band: tuple[float, float] | None = None     # Hz
    span: float | None = None                   # the operator's span setting
    drive_file: Path | None = None
    drive_unit: str | None = None               # a length unit
    drive_scale: float | None = None            # > 0
    drive_offset: float | str | None = None     # s the drive leads, or "auto"
    peak: float | None = None                   # m (peak_in, peak_mm or peak_m)
    seed: int | None = None
    frequency: float | None = None              # Hz (sine)
    record: str | None = None
    length_scale: float | None = None
    time_scale: float | None = None
    lead: float | None = None                   # s of rest before the target (a drive)
    notes: tuple[str, ...] = field(default=(), compare=False)

    def check_rate(self, fs: float, where: str) -> None:
        """Frequencies the command names must be below the run's Nyquist frequency."""
        nyq = fs / 2
        if self.band is not None and self.band[1] > nyq * (1 + 1e-9):
            raise VtableError(f"{where}.band_hz: {self.band[1]:g} Hz is above the run's "
                              f"Nyquist frequency {nyq:.6g} Hz (sampled at {fs:.6g} Hz)")
        if self.frequency is not None and self.frequency >= nyq:
            raise VtableError(f"{where}.frequency_hz: {self.frequency:g} Hz is at or above the "
                              f"run's Nyquist frequency {nyq:.6g} Hz (sampled at {fs:.6g} Hz)")


def _positive(d: dict[str, Any], key: str, where: str, unit: str = "1") -> float | None:
    if key not in d:
        return None
    x = check_number(d[key], f"{where}.{key}", unit)
    if not x > 0:
        raise VtableError(f"{where}.{key}: must be > 0, got {d[key]!r}")
    return x


def _text(d: dict[str, Any], key: str, where: str) -> str | None:
    if key not in d:
        return None
    if not isinstance(d[key], str) or not d[key].strip():
        raise VtableError(f"{where}.{key}: expected a non-empty string, got {d[key]!r}")
    return d[key]


def command_from_dict(d: Any, where: str, folder: Path | None = None) -> CommandDescription:
    """Parse and check a [command] table; `folder` resolves a relative drive_file (the
    folder of RUN.toml). Unknown keys are returned in `notes`."""
    if not isinstance(d, dict):
        raise VtableError(f"{where}: expected a table, got {type(d).__name__}")
    notes = [f"{where}: unknown key {k!r} (kept, not used){did_you_mean(k, COMMAND_KEYS)}"
             for k in d if k not in COMMAND_KEYS]
    kind = _text(d, "kind", where)
    if kind is not None and kind not in COMMAND_KINDS:
        raise VtableError(f"{where}.kind: expected one of {', '.join(COMMAND_KINDS)}, got "
                          f"{kind!r}")
    band = None
    if "band_hz" in d:
        b = d["band_hz"]
        if not isinstance(b, list) or len(b) != 2:
            raise VtableError(f"{where}.band_hz: expected [low, high] in Hz, got {b!r}")
        lo = check_number(b[0], f"{where}.band_hz", "Hz")
        hi = check_number(b[1], f"{where}.band_hz", "Hz")
        if not 0 <= lo < hi:
            raise VtableError(f"{where}.band_hz: expected 0 <= low < high, got "
                              f"[{lo:g}, {hi:g}]")
        band = (lo, hi)
    drive = None
    name = _text(d, "drive_file", where)
    if name is not None:
        drive = Path(name) if folder is None or Path(name).is_absolute() else folder / name
        if not drive.is_file():
            raise VtableError(f"{where}.drive_file: {str(drive)!r} is not a file")
    unit = _text(d, "drive_unit", where)
    if unit is not None:
        if not units.known(unit):
            raise VtableError(f"{where}.drive_unit: {unit!r} is not a known unit; expected a "
                              f"length unit ({', '.join(units.units_of('length'))})")
        units.check_dimension(unit, "length", f"{where}.drive_unit")
    offset: float | str | None = None
    if "drive_offset_s" in d:
        v = d["drive_offset_s"]
        offset = v if v == "auto" else check_number(v, f"{where}.drive_offset_s", "s")
    for k in ("drive_unit", "drive_scale", "drive_offset_s"):
        if k in d and name is None:
            notes.append(f"{where}: {k} without a drive_file (kept, not used)")
    if name is not None and unit is None:
        notes.append(f"{where}: drive_file without drive_unit: the drive is taken in inches "
                     "(the format's displacement unit)")
    peaks = [k for k in ("peak_in", "peak_mm", "peak_m") if k in d]
    if len(peaks) > 1:
        raise VtableError(f"{where}: {' and '.join(peaks)} both give the command's peak; "
                          "keep one")
    peak = _positive(d, peaks[0], where, peaks[0].split("_")[1]) if peaks else None
    seed = None
    if "seed" in d:
        seed = d["seed"]
        if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
            raise VtableError(f"{where}.seed: expected a whole number >= 0, got {seed!r}")
    return CommandDescription(
        kind=kind, band=band, span=_positive(d, "span", where), drive_file=drive,
        drive_unit=None if unit is None else units.canonical(unit),
        drive_scale=_positive(d, "drive_scale", where), drive_offset=offset,
        peak=peak, seed=seed,
        frequency=_positive(d, "frequency_hz", where, "Hz"), record=_text(d, "record", where),
        length_scale=_positive(d, "length_scale", where),
        time_scale=_positive(d, "time_scale", where), lead=_lead(d, where),
        notes=tuple(notes))


def _lead(d: dict[str, Any], where: str) -> float | None:
    """[command] lead_s: the seconds of rest a drive plays before its target, >= 0."""
    if "lead_s" not in d:
        return None
    x = check_number(d["lead_s"], f"{where}.lead_s", "s")
    if not x >= 0:
        raise VtableError(f"{where}.lead_s: must be >= 0 s, got {d['lead_s']!r}")
    return x
