"""Reading runs: RUN.toml + RUN.csv, or an HDF5 file with the same content, and a
campaign of runs of one configuration.

Errors are one line naming the file, the line, the column or the key and what was
expected. Things the format allows but a user should know about — unknown keys or
channels (kept), missing samples (kept as NaN, counted per channel), constant channels,
time stamps put on a uniform grid, a run without [specimen] — are collected in
`Run.reports`. The TOML is parsed once into `Run.declared` (`vtable.runs.meta`).

A drive file with drive_offset_s = "auto" is not aligned here: the lag is identified
from the table's response (`vtable.ident.drive.align`), a step of identification the
caller asks for.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from vtable.errors import VtableError
from vtable.runs.agree import RTOL, agree
from vtable.runs.assemble import assemble
from vtable.runs.csvfile import read_csv
from vtable.runs.hdf5 import read_hdf5
from vtable.runs.meta import Declaration, check_meta
from vtable.runs.model import Run
from vtable.runs.paths import read_text, run_paths, stem
from vtable.runs.timebase import check_time

__all__ = ["campaign", "check_time", "read_any", "read_meta", "read_run"]


def read_meta(toml_path: Path) -> Declaration:
    """Parse and check RUN.toml: its declaration, with the notes (unknown keys, ...)."""
    text = read_text(toml_path).removeprefix("\ufeff")
    try:
        meta = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise VtableError(f"{toml_path}: malformed TOML: {e}") from None
    return check_meta(meta, str(toml_path), toml_path.parent)


def read_run(path: str | Path) -> Run:
    """Read RUN.toml + RUN.csv (give either file or the common stem).

    Parameters
    ----------
    path
        ``RUN.toml``, ``RUN.csv`` or ``RUN``; a stem keeps its dots (``p10_scl0.1``).

    Returns
    -------
    Run
        Channels in SI; `declared` the TOML parsed; `reports` lists what the reader
        noticed and kept.

    Raises
    ------
    VtableError
        One line naming the file and the line, column or key.
    """
    toml_path, csv_path = run_paths(path)
    decl = read_meta(toml_path)
    header, data, notes = read_csv(csv_path)
    return assemble(str(stem(toml_path)), header, data, decl, [*decl.notes, *notes],
                    str(toml_path), csv_path, toml_path, 2, "line")


def read_any(path: str | Path) -> Run:
    """A run from RUN.toml/RUN.csv or an HDF5 file (.h5, .hdf5)."""
    p = Path(path)
    return read_hdf5(p) if p.suffix.lower() in (".h5", ".hdf5") else read_run(p)


def campaign(paths: list[str | Path]) -> list[Run]:
    """Runs of one configuration (`check_configuration`)."""
    runs = [read_any(p) for p in paths]
    if not runs:
        raise VtableError("a campaign needs at least one run")
    check_configuration(runs)
    return runs


def check_configuration(runs: list[Run]) -> None:
    """A campaign is one configuration: the runs' [table] and [control] agree, and their
    [specimen] agrees among the runs of one state ([specimen] state; the runs that declare
    none are one state). Runs of different states may declare different values of one kind
    of specimen (a building of as many storeys). Tables that differ as written agree when
    their declarations do (`vtable.runs.agree`: in one unit, within its tolerance), which
    a run's reports say when not exactly."""
    first: dict[str | None, Run] = {}
    for r in runs[1:]:
        for k in ("table", "control"):
            if not _same(r, runs[0], k):
                raise VtableError(f"{r.name}: [{k}] differs from {runs[0].name}'s; a campaign "
                                  "is one configuration")
    for r in runs:
        f = first.setdefault(r.state, r)
        if not _same(r, f, "specimen"):
            where = f" (state {r.state!r})" if r.state else ""
            raise VtableError(f"{r.name}: [specimen] differs from {f.name}'s{where}; runs of "
                              "one specimen state declare one specimen (declare [specimen] "
                              "state to tell states apart)")
    a = runs[0].specimen()
    for r in first.values():
        b = r.specimen()
        if type(a) is not type(b) or len(getattr(a, "weights", ())) != \
                len(getattr(b, "weights", ())):
            raise VtableError(f"{r.name}: its [specimen] (state {r.state!r}) is not the kind "
                              f"of specimen {runs[0].name} declares; the states of a campaign "
                              "are states of one specimen")


def _same(r: Run, f: Run, table: str) -> bool:
    """Whether run `r` declares `table` ("table", "control", "specimen") as run `f` does:
    as written, else as parsed within `agree.RTOL` (a unit or a key spelled otherwise;
    [control]'s knob positions, which have no units, exactly); not to the last digits,
    `r`'s reports say whose values the campaign takes (`f`'s)."""
    if r is f or r.configuration()[table] == f.configuration()[table]:
        return True
    a, b = getattr(f.declared, table), getattr(r.declared, table)
    if not agree(a, b, RTOL if table != "control" else 0.0):
        return False
    if not agree(a, b, EXACT):
        line = (f"{r.name}: its [{table}] agrees with {f.name}'s only within {RTOL:g} "
                f"(relative) once in one unit, not exactly: the campaign takes {f.name}'s "
                "values")
        if line not in r.reports:
            r.reports = [*r.reports, line]  # a new list: copies of the run keep theirs
    return True


#: two declared numbers closer than this (relative) are the same number (a unit's
#: conversion's last bits)
EXACT = 1e-12
