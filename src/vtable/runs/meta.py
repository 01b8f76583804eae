"""A run's TOML (docs/run-format.md, version 1) parsed and checked once
into a typed `Declaration`: the table the run was made on, the control settings, the
specimen, the command (with its drive file) and the unit overrides, all in SI.

Errors are one line naming the file and the key; what the format allows but a user
should know about (unknown keys, kept; no [table]; no [specimen]) is collected in
`Declaration.notes`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from vtable import units
from vtable.analytic.structure import specimen_frequencies
from vtable.errors import VtableError, did_you_mean
from vtable.params.specimen import (
    OPENSEES_DATA_KEYS,
    SPELLINGS,
    OpenSeesSpecimen,
    Specimen,
    specimen_from_dict,
    specimen_hints,
)
from vtable.runs.channels import channel_dimension
from vtable.runs.format import FORMAT, CommandDescription, check_control, command_from_dict
from vtable.runs.table import TableDescription, table_from_dict

#: the top-level keys of RUN.toml
TOP_KEYS = ("format", "title", "table", "control", "specimen", "command", "units")
#: the keys that must hold a TOML table
TABLE_KEYS = ("table", "control", "specimen", "command", "units")


@dataclass(frozen=True)
class Declaration:
    """What a run's TOML declares, parsed once (SI).

    `table` is None without a [table] (the models take the EERC table), `specimen` None
    without a [specimen] (a bare table), `command` None without a [command]; `units`
    holds the [units] overrides (channel -> unit), `control` the [control] knob positions
    per direction. `meta` is the TOML table it was parsed from."""

    title: str | None = None
    table: TableDescription | None = None
    control: dict[str, Any] = field(default_factory=dict)
    specimen: Specimen | None = None
    command: CommandDescription | None = None
    units: dict[str, str] = field(default_factory=dict)
    notes: tuple[str, ...] = field(default=(), compare=False)
    meta: dict[str, Any] = field(default_factory=dict, compare=False, repr=False)
    #: [specimen] state: the specimen's state the run was made in (None: not declared)
    state: str | None = None

    @property
    def drive_file(self) -> Path | None:
        """The drive file the controller played ([command] drive_file), or None."""
        return None if self.command is None else self.command.drive_file


def declare(meta: dict[str, Any], where: str, folder: Path | None = None) -> Declaration:
    """Parse the tables of a run's metadata (`where` prefixes messages, e.g. the TOML's
    path; `folder` resolves a relative drive_file). The top-level keys are not checked
    (`check_meta` does, for a file)."""
    for k in TABLE_KEYS:
        if k in meta and not isinstance(meta[k], dict):
            raise VtableError(f"{where}: [{k}] must be a table, got {type(meta[k]).__name__}")
    notes: list[str] = []
    table = None
    if "table" in meta:
        table = table_from_dict(meta["table"], f"{where} [table]")
        notes += table.notes
    else:
        notes.append(f"{where}: no [table]: the table the run was made on is not named")
    if "control" in meta:
        notes += check_control(meta["control"], f"{where} [control]")
    specimen, state = None, None
    if "specimen" in meta:
        given = dict(meta["specimen"])
        if "state" in given:
            state = given.pop("state")
            if not isinstance(state, str) or not state.strip() or state != state.strip() \
                    or state.startswith("("):
                raise VtableError(f"{where} [specimen].state: expected a name (a non-empty "
                                  "string, without spaces at its ends, not starting with "
                                  f"'('), got {state!r:.60}")
        specimen = specimen_from_dict(given, f"{where} [specimen]", folder)
        notes += specimen_hints(specimen, f"{where} [specimen]")
        if isinstance(specimen, OpenSeesSpecimen):  # its model as data, never run
            specimen, note = as_building(specimen, f"{where} [specimen]")
            notes.append(f"{where} [specimen]: {note}")
    else:
        notes.append(f"{where}: no [specimen]: treated as a bare table")
    command = None
    if "command" in meta:
        command = command_from_dict(meta["command"], f"{where} [command]", folder)
        notes += command.notes
    check_units(meta.get("units", {}), f"{where}: [units]")
    title = meta.get("title")
    return Declaration(title=title if isinstance(title, str) else None, table=table,
                       control=dict(meta.get("control", {})), specimen=specimen,
                       command=command,
                       units={k: units.canonical(u) for k, u in meta.get("units", {}).items()},
                       notes=tuple(notes), meta=meta, state=state)


def as_building(spec: OpenSeesSpecimen, where: str) -> tuple[Specimen, str]:
    """An OpenSees specimen as the shear building identification and diagnosis read: the
    model as data the run holds (`OpenSeesSpecimen.building`, written by `vtable simulate`).
    The model file is never run here: a run without that data is refused, saying how to
    get it."""
    name = Path(spec.model).name
    if spec.building is None:
        raise VtableError(f"{where}: the OpenSees model's floors, modes and damping are not "
                          f"in the run ({', '.join(OPENSEES_DATA_KEYS)}); a reader never "
                          f"runs {name}: make the run again with vtable simulate, which "
                          "writes them")
    n = spec.building.n
    return spec.building, (f"the OpenSees model {name} is read as the {n}-storey shear "
                           "building the run holds (its floors' masses and heights, "
                           f"modes and damping; {name} is not run)")


def check_meta(meta: dict[str, Any], where: str, folder: Path | None) -> Declaration:
    """A run file's metadata: the top-level keys checked, then every table parsed
    (`declare`); unknown keys are notes."""
    if meta.get("format") != FORMAT:
        raise VtableError(f"{where}: key 'format' must be {FORMAT!r}, got "
                          f"{meta.get('format')!r:.60}")
    if "title" in meta and not isinstance(meta["title"], str):
        raise VtableError(f"{where}: key 'title' must be a string, got {meta['title']!r:.60}")
    unknown = [f"{where}: unknown key {k!r} (kept, not used){did_you_mean(k, TOP_KEYS)}"
               for k in meta if k not in TOP_KEYS]
    d = declare(meta, where, folder)
    return replace(d, notes=(*unknown, *d.notes))


def check_units(d: Any, where: str) -> None:
    """Every [units] value is a known unit whose dimension is the channel's: a format
    channel takes units of its own dimension, `time` a time unit, other (extra) channels
    any known unit."""
    for ch, u in d.items():
        if not units.known(u):
            raise VtableError(f"{where} {ch} = {u!r} is not a known unit (e.g. in, mm, m, g, "
                              "m/s2, kip, N, rad)")
        dim = "time" if ch == "time" else channel_dimension(ch)
        if dim is not None:
            try:
                units.check_dimension(u, dim, "the time column" if ch == "time" else ch)
            except VtableError as e:
                raise VtableError(f"{where} {e}") from None


def check_against_rate(decl: Declaration, fs: float, where: str) -> None:
    """What the TOML says must be resolvable at the run's sampling rate: specimen
    frequencies and the command's band below the Nyquist frequency."""
    nyq = fs / 2
    if decl.specimen is not None:
        given = decl.meta.get("specimen", {})
        keys = ("frequency_hz", "frequencies_hz",
                *(k for s in ("stiffness_kip_per_in", "stiffnesses_kip_per_in")
                  for k in (s, *SPELLINGS[s][1])))  # as the run names them
        key = next((k for k in keys if k in given), "frequency")
        for f in specimen_frequencies(decl.specimen):
            if f >= nyq:
                raise VtableError(f"{where} [specimen].{key}: {f:.6g} Hz is at or above "
                                  f"the run's Nyquist frequency {nyq:.6g} Hz (sampled at "
                                  f"{fs:.6g} Hz)")
    if decl.command is not None:
        decl.command.check_rate(fs, f"{where} [command]")
