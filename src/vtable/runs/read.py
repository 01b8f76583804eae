"""Reading, validating and writing runs (CSV + TOML, and HDF5 with the same content).

Errors are one line naming the file, the key or the column and what was expected.
Things the format allows but a user should know about — unknown keys or channels (kept),
missing samples (kept as NaN, counted per channel) — are collected in `Run.reports`.
"""

from __future__ import annotations

import csv
import io
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from vtable import units as un
from vtable.errors import VtableError
from vtable.runs.format import FORMAT, dumps_toml
from vtable.runs.model import FORMAT_UNITS, TOP_KEYS, Run

UNIFORM_TOL = 1e-6


def _paths(path: str | Path) -> tuple[Path, Path]:
    p = Path(path)
    stem = p.with_suffix("") if p.suffix in (".toml", ".csv") else p
    return stem.with_suffix(".toml"), stem.with_suffix(".csv")


def _read_text(p: Path) -> str:
    try:
        return p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise VtableError(f"{p}: no such file") from None
    except UnicodeDecodeError:
        raise VtableError(f"{p}: not UTF-8 text") from None
    except OSError as e:
        raise VtableError(f"{p}: cannot read: {e.strerror}") from None


def read_meta(toml_path: Path) -> tuple[dict[str, Any], list[str]]:
    """Parse and check RUN.toml; returns the table and the reports (unknown keys)."""
    text = _read_text(toml_path)
    try:
        meta = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise VtableError(f"{toml_path}: malformed TOML: {e}") from None
    if meta.get("format") != FORMAT:
        raise VtableError(f"{toml_path}: key 'format' must be {FORMAT!r}, got "
                          f"{meta.get('format')!r}")
    reports = [f"{toml_path}: unknown key {k!r} (kept)" for k in meta if k not in TOP_KEYS]
    for k in ("table", "control", "specimen", "command", "units"):
        if k in meta and not isinstance(meta[k], dict):
            raise VtableError(f"{toml_path}: [{k}] must be a table")
    units = meta.get("units", {})
    for ch, u in units.items():
        if not isinstance(u, str) or u not in un.UNITS:
            raise VtableError(f"{toml_path}: [units] {ch} = {u!r} is not a known unit "
                              f"(e.g. in, mm, m, g, m/s2, kip, N, rad)")
    if "specimen" in meta:
        from vtable.params.specimen import specimen_from_dict

        specimen_from_dict(meta["specimen"], f"{toml_path} [specimen]")
    return meta, reports


def parse_csv(text: str, where: Path) -> tuple[list[str], np.ndarray, dict[str, int]]:
    """Header and values (NaN for `nan` or empty), checked cell by cell."""
    rows = list(csv.reader(io.StringIO(text)))
    if not rows or not rows[0] or not any(c.strip() for c in rows[0]):
        raise VtableError(f"{where}: empty file; expected a header line starting with 'time'")
    header = [h.strip() for h in rows[0]]
    if header[0] != "time":
        raise VtableError(f"{where}: the first column must be 'time', got {header[0]!r}")
    seen = set()
    for h in header:
        if not h:
            raise VtableError(f"{where}: empty column name in the header")
        if h in seen:
            raise VtableError(f"{where}: duplicate column {h!r}")
        seen.add(h)
    body = [r for r in rows[1:] if r and any(c.strip() for c in r)]
    if len(body) < 2:
        raise VtableError(f"{where}: needs at least two samples, got {len(body)}")
    data = np.empty((len(body), len(header)))
    for i, r in enumerate(body, start=2):
        if len(r) != len(header):
            raise VtableError(f"{where}: line {i} has {len(r)} fields, the header "
                              f"{len(header)}")
        for j, cell in enumerate(r):
            c = cell.strip()
            if c == "" or c.lower() == "nan":
                data[i - 2, j] = np.nan
                continue
            try:
                v = float(c)
            except ValueError:
                raise VtableError(f"{where}: line {i}, column {header[j]!r}: {c[:20]!r} is "
                                  "not a number") from None
            if math.isinf(v):
                raise VtableError(f"{where}: line {i}, column {header[j]!r}: infinite value")
            data[i - 2, j] = v
    missing = {h: int(np.isnan(data[:, j]).sum()) for j, h in enumerate(header)}
    return header, data, missing


def check_time(t: np.ndarray, where: Path) -> None:
    if np.isnan(t).any():
        raise VtableError(f"{where}: column 'time' has missing samples")
    steps = np.diff(t)
    med = float(np.median(steps))
    if not med > 0:
        raise VtableError(f"{where}: column 'time' must increase")
    bad = np.abs(steps - med) > UNIFORM_TOL * med
    if bad.any():
        i = int(np.argmax(bad))
        raise VtableError(f"{where}: column 'time' is not uniform: step {steps[i]:.9g} s at "
                          f"line {i + 3} vs median {med:.9g} s")


def read_run(path: str | Path) -> Run:
    """Read RUN.toml + RUN.csv (give either file or the common stem)."""
    toml_path, csv_path = _paths(path)
    meta, reports = read_meta(toml_path)
    header, data, missing = parse_csv(_read_text(csv_path), csv_path)
    check_time(data[:, 0], csv_path)
    overrides = meta.get("units", {})
    channels, units, extra = {}, {}, []
    for j, h in enumerate(header[1:], start=1):
        unit = overrides.get(h, FORMAT_UNITS.get(h))
        if h not in FORMAT_UNITS:
            extra.append(h)
        units[h] = unit or "1"
        channels[h] = un.to_si(data[:, j], units[h]) if unit else data[:, j].copy()
    if extra:
        no_unit = [h for h in extra if h not in overrides]
        reports.append(f"{csv_path}: {len(extra)} column(s) not in the format, kept: "
                       + ", ".join(extra[:6]) + (", ..." if len(extra) > 6 else "")
                       + (f" ({len(no_unit)} without a unit)" if no_unit else ""))
    for h in overrides:
        if h not in channels:
            reports.append(f"{toml_path}: [units] names {h!r}, which is not a column")
    miss = {h: n for h, n in missing.items() if n and h != "time"}
    for h, n in miss.items():
        reports.append(f"{csv_path}: column {h!r} has {n} missing samples (kept as NaN, "
                       "not filled)")
    return Run(name=str(toml_path.with_suffix("")), time=data[:, 0].copy(), channels=channels,
               units=units, meta=meta, source=toml_path, missing=miss, extra=extra,
               reports=reports)


def write_run(run: Run, path: str | Path) -> tuple[Path, Path]:
    """Write RUN.csv + RUN.toml (channels back in their file units, exact floats)."""
    toml_path, csv_path = _paths(path)
    toml_path.parent.mkdir(parents=True, exist_ok=True)
    names = list(run.channels)
    cols = [run.time] + [un.from_si(run.channels[h], run.units.get(h, "1"))
                         if run.units.get(h, "1") in un.UNITS else run.channels[h]
                         for h in names]
    data = np.column_stack(cols)
    with csv_path.open("w", encoding="utf-8", newline="\n") as fh:
        fh.write(",".join(["time", *names]) + "\n")
        for row in data:
            fh.write(",".join("nan" if math.isnan(v) else repr(float(v)) for v in row) + "\n")
    meta = dict(run.meta)
    meta["format"] = FORMAT
    overrides = {h: u for h, u in run.units.items()
                 if FORMAT_UNITS.get(h) != u and not (h not in FORMAT_UNITS and u == "1")}
    if overrides:
        meta["units"] = overrides
    else:
        meta.pop("units", None)
    ordered = {"format": FORMAT, **{k: v for k, v in meta.items() if k != "format"}}
    toml_path.write_text(dumps_toml(ordered), encoding="utf-8")
    return csv_path, toml_path


def write_hdf5(run: Run, path: str | Path) -> Path:
    """The same content in one HDF5 file: /time, /channels/<name> (file units), and the
    TOML metadata as the attribute 'toml'."""
    import h5py

    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    meta = {**run.meta, "format": FORMAT, "units": dict(run.units)}
    with h5py.File(p, "w") as f:
        f.attrs["toml"] = dumps_toml({"format": FORMAT, **{k: v for k, v in meta.items()
                                                             if k != "format"}})
        f.create_dataset("time", data=run.time)
        g = f.create_group("channels")
        for h, v in run.channels.items():
            unit = run.units.get(h, "1")
            g.create_dataset(h, data=un.from_si(v, unit) if unit in un.UNITS else v,
                             compression="gzip")
        f.attrs["order"] = list(run.channels)
    return p


def read_hdf5(path: str | Path) -> Run:
    """Read a run written by `write_hdf5` (same checks as the CSV reader)."""
    import h5py

    p = Path(path)
    try:
        f = h5py.File(p, "r")
    except FileNotFoundError:
        raise VtableError(f"{p}: no such file") from None
    except OSError:
        raise VtableError(f"{p}: not an HDF5 run file") from None
    with f:
        try:
            meta = tomllib.loads(f.attrs["toml"])
            t = np.asarray(f["time"], dtype=float)
            order = [str(x) for x in f.attrs["order"]]
            raw = {h: np.asarray(f["channels"][h], dtype=float) for h in order}
        except (KeyError, tomllib.TOMLDecodeError) as e:
            raise VtableError(f"{p}: missing or malformed run content ({e})") from None
    if meta.get("format") != FORMAT:
        raise VtableError(f"{p}: attribute 'toml' must declare format {FORMAT!r}")
    check_time(t, p)
    units = meta.pop("units", {})
    channels = {h: un.to_si(v, units.get(h, "1")) for h, v in raw.items()}
    missing = {h: int(np.isnan(v).sum()) for h, v in channels.items() if np.isnan(v).any()}
    extra = [h for h in channels if h not in FORMAT_UNITS]
    override = {h: u for h, u in units.items() if FORMAT_UNITS.get(h) != u and u != "1"}
    if override:
        meta["units"] = override
    return Run(name=str(p.with_suffix("")), time=t, channels=channels,
               units={h: units.get(h, "1") for h in channels}, meta=meta, source=p,
               missing=missing, extra=extra,
               reports=[f"{p}: column {h!r} has {n} missing samples" for h, n in missing.items()])


def read_any(path: str | Path) -> Run:
    p = Path(path)
    return read_hdf5(p) if p.suffix in (".h5", ".hdf5") else read_run(p)


def campaign(paths: list[str | Path]) -> list[Run]:
    """Runs of one configuration: table, control settings and specimen must agree."""
    runs = [read_any(p) for p in paths]
    if not runs:
        raise VtableError("a campaign needs at least one run")
    ref = runs[0].configuration()
    for r in runs[1:]:
        cfg = r.configuration()
        for k in ref:
            if cfg[k] != ref[k]:
                raise VtableError(f"{r.name}: [{k}] differs from {runs[0].name}'s; a campaign "
                                  "is one configuration")
    return runs
