"""A Rerun recording written to an .rrd file atomically: the stream goes to a temporary
file beside the target, which is renamed into place once the recording is complete (footer
written), so a killed or failed run never leaves a truncated .rrd under the asked name."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import rerun as rr

from vtable.errors import VtableError
from vtable.fileio import atomic_path


@contextlib.contextmanager
def rrd_file(path: str | Path, application_id: str) -> Iterator[rr.RecordingStream]:
    """A `RecordingStream` saving to `path` (complete or absent when the block ends)."""
    p = Path(path)
    with atomic_path(p) as tmp:
        rec = rr.RecordingStream(application_id)
        rec.save(str(tmp))
        try:
            yield rec
        finally:
            rec.flush()
            rec.disconnect()
        if tmp != p and (not tmp.exists() or tmp.stat().st_size == 0):
            raise VtableError(f"{p}: cannot write: the recording is empty")
