"""LNEC's measured run (../shared/data/real, README there) for the tests that read it:
where it is (VTABLE_REAL_DATA, or the shared folder beside the repository), the skip mark
when it is absent, and a copy with its CSV decompressed."""

from __future__ import annotations

import gzip
import os
import shutil
from pathlib import Path

import pytest

NAME = "lnec_pink_2"


def folder() -> Path | None:
    """The folder holding lnec_pink_2.toml and .csv.gz, or None."""
    root = Path(__file__).resolve().parents[1]
    env = os.environ.get("VTABLE_REAL_DATA")
    for d in ([Path(env)] if env else []) + [root.parent / "shared/data/real",
                                              root.parent.parent / "shared/data/real"]:
        if (d / f"{NAME}.toml").is_file() and (d / f"{NAME}.csv.gz").is_file():
            return d
    return None


#: skips a test when the run is not beside the repository
NEEDED = pytest.mark.skipif(folder() is None, reason="../shared/data/real is not beside the repo")


def copy_run(dest: Path) -> Path:
    """The run copied into `dest` with its CSV decompressed; its TOML's path."""
    src = folder()
    assert src is not None
    shutil.copy(src / f"{NAME}.toml", dest)
    with gzip.open(src / f"{NAME}.csv.gz", "rb") as a, open(dest / f"{NAME}.csv", "wb") as b:
        shutil.copyfileobj(a, b)
    return dest / f"{NAME}.toml"
