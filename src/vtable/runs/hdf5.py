"""A run in one HDF5 file: /time (s), /channels/<name> (file units), the TOML metadata
(with every channel's unit in [units]) as the attribute 'toml', the channel order as the
attribute 'order'. Read with the checks of the CSV reader."""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from vtable import fileio
from vtable import units as un
from vtable.errors import VtableError
from vtable.runs.assemble import assemble
from vtable.runs.channels import FORMAT_UNITS
from vtable.runs.format import dumps_toml
from vtable.runs.meta import check_meta
from vtable.runs.model import Run
from vtable.runs.write import check_writable, file_meta

#: the attributes of a run file (the metadata, the channel order)
ATTRIBUTES = ("toml", "order")


def write_hdf5(run: Run, path: str | Path) -> Path:
    """The same content in one HDF5 file: /time (s), /channels/<name> (file units), the
    TOML metadata (with every channel's unit in [units]) as the attribute 'toml', the
    channel order as the attribute 'order'. Written to a temporary file and renamed."""
    p = Path(path)
    names = check_writable(run)
    meta = {**file_meta(run), "units": {h: run.units.get(h, "1") for h in names}}
    text = dumps_toml(meta)
    import h5py  # start-up: only a run in HDF5 needs it

    with fileio.atomic_path(p) as tmp:
        with h5py.File(tmp, "w") as f:
            f.attrs["toml"] = text
            f.create_dataset("time", data=np.asarray(run.time, dtype=float))
            g = f.create_group("channels")
            for h in names:
                g.create_dataset(h, data=un.from_si(np.asarray(run.channels[h], dtype=float),
                                                    run.units.get(h, "1")),
                                 compression="gzip")
            f.attrs["order"] = names
    return p


def read_hdf5(path: str | Path) -> Run:
    """Read a run written by `write_hdf5` (the checks of the CSV reader)."""
    p = Path(path)
    if not p.is_file():
        raise VtableError(f"{p}: no such file" if not p.exists() else f"{p}: not a file")
    import h5py  # start-up: only a run in HDF5 needs it

    try:
        f = h5py.File(p, "r")
    except OSError:
        raise VtableError(f"{p}: not an HDF5 file (or a damaged one)") from None
    try:
        with f:
            text = f.attrs.get("toml")
            if isinstance(text, bytes):
                text = text.decode("utf-8")
            if not isinstance(text, str):
                raise VtableError(f"{p}: no 'toml' attribute; not a vtable run file")
            try:
                meta = tomllib.loads(text)
            except tomllib.TOMLDecodeError as e:
                raise VtableError(f"{p}: attribute 'toml' is malformed TOML: {e}") from None
            if "time" not in f or "channels" not in f:
                raise VtableError(f"{p}: needs the datasets /time and /channels/<name>")
            group = f["channels"]
            order = [str(x) for x in f.attrs.get("order", [])]
            extra = sorted(set(f.attrs) - set(ATTRIBUTES))
            members = list(group.keys())
            if sorted(order) != sorted(members) or "time" in order:
                raise VtableError(f"{p}: attribute 'order' does not list the datasets of "
                                  "/channels")
            n = _dataset(f["time"], "time", p, None)
            data = np.empty((len(order) + 1, n))
            f["time"].read_direct(data[0])
            for j, h in enumerate(order, start=1):
                _dataset(group[h], h, p, n)
                group[h].read_direct(data[j])  # straight into the array: no copies
    except VtableError:
        raise
    except (OSError, KeyError, ValueError, TypeError, RuntimeError, UnicodeDecodeError) as e:
        why = " ".join(str(e).split())[:120]
        raise VtableError(f"{p}: damaged or not a vtable run file ({why})") from None
    decl = check_meta(meta, str(p), p.parent)  # [units] names every channel's unit
    meta.pop("units", None)
    units = dict(decl.units)  # in the spelling of `vtable.units.UNITS`
    unnamed = [h for h in order if h in FORMAT_UNITS and h not in units]
    override = {h: u for h, u in units.items() if FORMAT_UNITS.get(h) != u and u != "1"}
    if override:
        meta["units"] = override
    if n < 2:
        raise VtableError(f"{p}: needs at least two samples, got {n}")
    decl = dataclasses.replace(decl, units=override, meta=meta)
    file_units = {**units, **{h: units.get(h, "1") for h in order}}
    notes = [*decl.notes, *(f"{p}: attribute {a!r} not read (a run file's attributes are "
                            f"{' and '.join(map(repr, ATTRIBUTES))}; its units are the "
                            "[units] table in 'toml')" for a in extra)]
    if unnamed:
        notes.append(f"{p}: the [units] table in 'toml' names no unit for {len(unnamed)} of "
                     f"{len(order)} channels ({', '.join(unnamed[:4])}"
                     f"{', ...' if len(unnamed) > 4 else ''}): read in the format's units "
                     "(a run file in HDF5 names every channel's)")
    return assemble(str(_stem_h5(p)), ["time", *order], data, decl, notes, str(p),
                    p, p, 0, "sample", file_units=file_units)


def _stem_h5(p: Path) -> Path:
    return p.with_name(p.name[: -len(p.suffix)]) if p.suffix else p


def _dataset(ds: Any, name: str, p: Path, n: int | None) -> int:
    """Check a dataset is 1-D, numeric and (for a channel) as long as /time; its length."""
    import h5py  # loaded by the reader already

    if not isinstance(ds, h5py.Dataset) or ds.ndim != 1 or ds.dtype.kind not in "fiu":
        raise VtableError(f"{p}: {name!r} must be a one-dimensional numeric dataset")
    if n is not None and ds.shape[0] != n:
        raise VtableError(f"{p}: channel {name!r} has {ds.shape[0]} samples, /time {n}")
    return int(ds.shape[0])

