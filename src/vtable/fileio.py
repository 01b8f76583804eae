"""Writing files the safe way: every file vtable writes appears complete or not at all.

Each write goes to a temporary file in the target folder, is flushed to disk, then
renamed over the target (`os.replace`, atomic on POSIX). A target that exists and is not
a regular file (a device such as /dev/null, a pipe) is written directly: it is never
replaced. A write that fails (read-only folder, full disk, a path that is a folder) is one
`VtableError` line naming the path, and leaves no temporary file behind.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from vtable.errors import VtableError


def _umask() -> int:
    m = os.umask(0)
    os.umask(m)
    return m


_UMASK = _umask()


def _fail(path: Path, e: OSError) -> VtableError:
    why = e.strerror or type(e).__name__
    return VtableError(f"{path}: cannot write: {why}")


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path in the target's folder to write to (by any library); renamed to
    `path` when the block ends without an exception, removed otherwise."""
    p = Path(path)
    if p.exists() and not p.is_file() and not p.is_dir():  # a device or a pipe
        try:
            yield p
        except OSError as e:
            raise _fail(p, e) from None
        return
    if p.is_dir():
        raise VtableError(f"{p}: cannot write: is a folder")
    for up in p.parents:
        if up.exists():
            if not up.is_dir():
                raise VtableError(f"{p}: cannot write: {up} is a file, not a folder")
            break
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent)
        os.close(fd)
        os.chmod(tmp, 0o666 & ~_UMASK)  # as a plain open() would create it
    except OSError as e:
        raise _fail(p, e) from None
    tmp_p = Path(tmp)
    try:
        yield tmp_p
        with open(tmp_p, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp_p, p)
    except OSError as e:
        _remove(tmp_p)
        raise _fail(p, e) from None
    except BaseException:
        _remove(tmp_p)
        raise


@contextlib.contextmanager
def atomic_open(path: str | Path, mode: str = "w", **kw: Any) -> Iterator[IO]:
    """`open(path, mode)` that writes a temporary file and renames it on success."""
    if not mode.startswith("w"):
        raise ValueError("atomic_open writes only")
    p = Path(path)
    with atomic_path(p) as tmp:
        try:
            fh = open(tmp, mode, **kw)
        except OSError as e:
            raise _fail(p, e) from None
        try:
            with fh:
                yield fh
                fh.flush()
        except OSError as e:
            raise _fail(p, e) from None


def write_text(path: str | Path, text: str) -> Path:
    """Write UTF-8 text atomically; returns the path."""
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(text)
    return Path(path)


def write_bytes(path: str | Path, data: bytes) -> Path:
    """Write bytes atomically; returns the path."""
    with atomic_open(path, "wb") as fh:
        fh.write(data)
    return Path(path)


def _remove(p: Path) -> None:
    with contextlib.suppress(OSError):
        p.unlink()
