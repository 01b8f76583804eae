"""Run CSV files a warm process (`vtable.warm`) parsed between commands, for its next
commands' children (forked from it) to take instead of parsing them again: the README
campaign's three files take ~0.17 s to parse, their bytes ~10 ms to read and hash.

A command's child notes the files it parsed (`parsed_here`); the warm process parses them
after it (`keep`); `kept` gives a parse only while the file's bytes are those parsed
(their BLAKE2 digest, whatever the file's times say), as copies.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

#: the samples kept at most (bytes): the oldest files are dropped beyond
MAX_BYTES = 256 << 20

#: absolute path -> (the file read: the path or its .gz, its digest, header, samples, notes)
_KEPT: dict[str, tuple[Path, bytes, list[str], np.ndarray, list[str]]] = {}
_PARSED: list[str] = []  # the files parsed in this process (`parsed_here`)


def source(path: Path) -> Path:
    """The file `csvfile.parse_csv` reads for `path`: itself, or its .gz when it is absent."""
    return path if path.exists() else path.with_name(path.name + ".gz")


def _digest(path: Path) -> bytes | None:
    try:
        with path.open("rb") as fh:
            return hashlib.file_digest(fh, lambda: hashlib.blake2b(digest_size=20)).digest()
    except OSError:
        return None


def kept(path: Path) -> tuple[list[str], np.ndarray, list[str]] | None:
    """`csvfile.parse_csv(path)` as kept (copies), when the file read then still holds the
    same bytes; else None."""
    key = os.path.abspath(path)
    entry = _KEPT.get(key)
    if entry is None:
        return None
    read, digest, header, data, notes = entry
    if source(Path(key)) != read or _digest(read) != digest:
        return None
    return list(header), data.copy(), list(notes)


def note(path: Path) -> None:
    """`path` was parsed here (a warm process's child tells its warm process)."""
    _PARSED.append(os.path.abspath(path))


def parsed_here() -> list[str]:
    """The files parsed in this process, in order, once each."""
    return list(dict.fromkeys(_PARSED))


def keep(path: str) -> bool:
    """Parse `path` and keep it (a warm process, between commands); nothing kept (False)
    when the file changed while it was parsed or cannot be parsed (the command said
    why)."""
    from vtable.runs.csvfile import parse_csv

    read = source(Path(path))
    digest = _digest(read)
    try:
        header, data, notes = parse_csv(Path(path))
    except Exception:  # (the command that read it reported it)
        return False
    if digest is None or _digest(read) != digest:
        return False
    data.flags.writeable = False
    _KEPT.pop(path, None)
    _KEPT[path] = (read, digest, header, data, notes)
    while sum(e[3].nbytes for e in _KEPT.values()) > MAX_BYTES and len(_KEPT) > 1:
        _KEPT.pop(next(iter(_KEPT)))
    return True
