"""Run CSV files a warm process (`vtable.warm`) parsed between commands, for its next
commands' children (forked from it) to take instead of parsing them again: the README
campaign's three files take ~0.19 s to parse, their bytes ~10 ms to read and hash.

A command's child notes the files it parsed (`noting`, `note`, `parsed_here`); the warm
process parses them after it (`keep`); `kept` gives a parse only while the file's bytes
are those parsed (their BLAKE2 digest, whatever the file's times say), as copies. A file
is known by the real path of the file opened (links resolved). Only a plain file that
parsed without a note is kept (a compressed one, or one whose last line has no line end,
is parsed each time: its notes name the path as the command gave it), and only one of at
most `FILE_MAX` bytes (a larger one would hold the warm process from its next command
while it parses).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

#: the samples kept at most (bytes): the oldest files are dropped beyond
MAX_BYTES = 256 << 20
#: the largest file kept (bytes of text: ~0.5 s to parse)
FILE_MAX = 16 << 20

#: real path -> (its digest, header, samples)
_KEPT: dict[str, tuple[bytes, list[str], np.ndarray]] = {}
_PARSED: list[str] = []  # the files parsed in this process since `noting`
_NOTING = [False]


def _real(path: Path) -> str | None:
    """The real path of the plain file `csvfile.parse_csv` opens for `path`, or None when
    it would open none (or its .gz)."""
    return os.path.realpath(path) if os.path.isfile(path) else None


def _digest(path: str) -> bytes | None:
    try:
        with open(path, "rb") as fh:
            return hashlib.file_digest(fh, lambda: hashlib.blake2b(digest_size=20)).digest()
    except OSError:
        return None


def kept(path: Path) -> tuple[list[str], np.ndarray, list[str]] | None:
    """`csvfile.parse_csv(path)` as kept (copies), when the file holds the bytes parsed;
    else None."""
    real = _real(path) if _KEPT else None
    entry = _KEPT.get(real) if real is not None else None
    if entry is None or _digest(real) != entry[0]:
        return None
    return list(entry[1]), entry[2].copy(), []


def noting() -> None:
    """From now on, `note` the files parsed here (a warm process's child, for its warm
    process)."""
    _PARSED.clear()
    _NOTING[0] = True


def note(path: Path, notes: list[str]) -> None:
    """`path` was parsed here, with `notes`: one a warm process may keep (`noting`)."""
    real = _real(path)
    if _NOTING[0] and not notes and real is not None:
        _PARSED.append(real)


def parsed_here() -> list[str]:
    """The files noted here, once each."""
    return list(dict.fromkeys(_PARSED))


def keep(path: str, parse: Callable[[Path], tuple[list[str], np.ndarray, list[str]]]
         ) -> bool:
    """`parse` (`csvfile.parse_csv`) the file at the real path `path` and keep it (a warm
    process, between commands). Nothing is kept (False, and what was kept of it dropped)
    when it is larger than `FILE_MAX`, changed while it was parsed, cannot be parsed
    (the command said why) or parses with notes."""
    _KEPT.pop(path, None)
    try:
        if os.path.getsize(path) > FILE_MAX:
            return False
        digest = _digest(path)
        header, data, notes = parse(Path(path))
    except Exception:  # (the command that read it reported it)
        return False
    if notes or digest is None or _digest(path) != digest or data.nbytes > MAX_BYTES:
        return False
    data.flags.writeable = False
    _KEPT[path] = (digest, header, data)
    while sum(e[2].nbytes for e in _KEPT.values()) > MAX_BYTES:
        _KEPT.pop(next(iter(_KEPT)))
    return True
