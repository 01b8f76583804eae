"""Where a run's files are: RUN.toml and RUN.csv share a stem; text files are read as
UTF-8 with one-line errors."""

from __future__ import annotations

from pathlib import Path

from vtable.errors import VtableError


def stem(path: str | Path) -> Path:
    """The common stem of RUN.toml and RUN.csv: the path without a .toml or .csv suffix
    (other dots are part of the stem: p10_scl0.1, run.txt)."""
    p = Path(path)
    if p.suffix.lower() in (".toml", ".csv"):
        return p.with_name(p.name[: -len(p.suffix)])
    return p


def run_paths(path: str | Path) -> tuple[Path, Path]:
    """(RUN.toml, RUN.csv) of a run given by either file or the common stem."""
    s = stem(path)
    return s.with_name(s.name + ".toml"), s.with_name(s.name + ".csv")


def read_text(p: Path) -> str:
    """A text file's content (UTF-8, a BOM dropped); NUL bytes, bad encodings and missing
    files are one-line errors."""
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise VtableError(f"{p}: no such file") from None
    except IsADirectoryError:
        raise VtableError(f"{p}: is a folder, not a file") from None
    except OSError as e:
        raise VtableError(f"{p}: cannot read: {e.strerror or type(e).__name__}") from None
    if b"\x00" in data:
        raise VtableError(f"{p}: binary data (NUL bytes), not a text file")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise VtableError(f"{p}: not UTF-8 text (byte {e.start})") from None

