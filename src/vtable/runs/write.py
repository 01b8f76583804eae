"""Writing runs: RUN.csv + RUN.toml, channels back in their file units, exact floats,
safe against a kill."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from vtable import display, fileio
from vtable import units as un
from vtable.errors import VtableError
from vtable.runs.channels import FORMAT_UNITS
from vtable.runs.format import FORMAT, dumps_toml
from vtable.runs.model import Run
from vtable.runs.paths import run_paths


def file_meta(run: Run) -> dict[str, Any]:
    """The run's metadata as a file holds it: the format key first; [units] for the
    channels not in the format's units, or, for a metric run (`display.run_family`: a
    simulated run on a metric table is written in mm, mm/s, g, kN), for every channel: its
    file says its units in full, as a metric lab's do."""
    meta = {k: v for k, v in run.meta.items() if k != "format"}
    every = display.run_family(run) == "metric"
    overrides = {h: u for h, u in run.units.items() if h in run.channels
                 and (every or FORMAT_UNITS.get(h) != u)
                 and not (h not in FORMAT_UNITS and u == "1")}
    if overrides:
        meta["units"] = overrides
    else:
        meta.pop("units", None)
    return {"format": FORMAT, **meta}


def check_writable(run: Run) -> list[str]:
    names = list(run.channels)
    n = len(run.time)
    if n < 2 or not np.all(np.isfinite(run.time)):
        raise VtableError(f"{run.name}: the time base needs two or more finite samples")
    for h in names:
        if not h or h == "time" or any(c in h for c in ',"\r\n') or h != h.strip():
            raise VtableError(f"{run.name}: channel name {h!r} cannot be a CSV column")
        if len(run.channels[h]) != n:
            raise VtableError(f"{run.name}: channel {h!r} has {len(run.channels[h])} samples, "
                              f"the time base {n}")
        u = run.units.get(h, "1")
        if not un.known(u):
            raise VtableError(f"{run.name}: channel {h!r} has unit {u!r}, not a known unit")
        if np.isinf(run.channels[h]).any():
            raise VtableError(f"{run.name}: channel {h!r} has infinite values; a run file "
                              "cannot hold them")
    return names


def write_run(run: Run, path: str | Path) -> tuple[Path, Path]:
    """Write RUN.csv + RUN.toml (channels back in their file units, exact floats).

    Safe against a kill: the old RUN.toml is removed first, RUN.csv is written to a
    temporary file and renamed, RUN.toml last (also atomically). An interrupted write
    leaves no RUN.toml, so no reader takes the pair for a run."""
    toml_path, csv_path = run_paths(path)
    names = check_writable(run)
    toml_text = dumps_toml(file_meta(run))
    try:
        toml_path.unlink(missing_ok=True)
    except OSError as e:
        raise VtableError(f"{toml_path}: cannot remove the old file: "
                          f"{e.strerror or type(e).__name__}") from None
    rows = 20000
    with fileio.atomic_open(csv_path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(",".join(["time", *names]) + "\n")
        for r0 in range(0, len(run.time), rows):
            cols = [run.time[r0:r0 + rows]] + [
                un.from_si(np.asarray(run.channels[h][r0:r0 + rows], dtype=float),
                           run.units.get(h, "1")) for h in names]
            block = np.column_stack(cols).tolist()
            fh.write("".join(",".join(map(repr, row)) + "\n" for row in block))
    fileio.write_text(toml_path, toml_text)
    return csv_path, toml_path

