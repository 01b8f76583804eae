"""RUN.csv: the header and the samples, read in blocks straight into one preallocated
float64 array (a row per column), so reading costs about the size of the samples in
memory, not of the text.

A cell is plain ASCII decimal or scientific notation, ``nan`` (also ``NaN``, ``NAN``) or
empty for a missing sample; Python's other float spellings (``1_000``, full-width or
Arabic-Indic digits, ``inf``, ``infinity``) are refused. Errors are one line naming the
file, the line and the column.
"""

from __future__ import annotations

import csv
import gzip
import math
import re
import zlib
from pathlib import Path
from typing import IO

import numpy as np

from vtable.errors import VtableError
from vtable.runs import parsed

BLOCK = 1 << 20  # bytes read at a time (the reader needs about 10 blocks beyond the samples)
HEADER_MAX = 1 << 20

_BOM = b"\xef\xbb\xbf"
_ALLOWED = np.zeros(256, dtype=bool)
_ALLOWED[np.frombuffer(b"0123456789+-.eEnaNA ,\n", dtype=np.uint8)] = True
_NUMBER = re.compile(rb"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NANS = {s + n for s in (b"", b"+", b"-") for n in (b"nan", b"NaN", b"NAN")}


def _header(first: bytes, where: Path) -> list[str]:
    if first.startswith(_BOM):
        first = first[len(_BOM):]
    if b"\x00" in first:
        raise VtableError(f"{where}: binary data (NUL bytes), not a CSV text file")
    try:
        text = first.decode("utf-8").rstrip("\r\n")
    except UnicodeDecodeError as e:
        raise VtableError(f"{where}: line 1 is not UTF-8 text (byte {e.start})") from None
    if not text.strip():
        raise VtableError(f"{where}: empty file; expected a header line starting with 'time'")
    if "\r" in text:
        raise VtableError(f"{where}: line 1 holds a lone carriage return (old Mac line ends?); "
                          "expected lines ending in LF or CRLF")
    try:
        header = [h.strip() for h in next(csv.reader([text]))]
    except csv.Error as e:
        raise VtableError(f"{where}: line 1: malformed header ({e})") from None
    if len(header) == 1 and (";" in text or "\t" in text):
        sep = "';'" if ";" in text else "tabs"
        raise VtableError(f"{where}: line 1 is separated by {sep}; expected comma-separated "
                          "values")
    if header[0] != "time":
        raise VtableError(f"{where}: the first column must be 'time', got {header[0]!r:.40}")
    seen = set()
    for h in header:
        if not h:
            raise VtableError(f"{where}: empty column name in the header")
        if h in seen:
            raise VtableError(f"{where}: duplicate column {h!r}")
        seen.add(h)
    return header


class _Reader:
    """Fills a (columns x rows) float64 array block by block."""

    def __init__(self, where: Path, header: list[str], rows: int) -> None:
        self.where, self.header, self.m = where, header, len(header)
        self.data = np.empty((self.m, rows))
        self.row = 0
        self.blank_line: int | None = None  # first empty line (only trailing ones allowed)

    @property
    def line(self) -> int:
        """File line of the next row (line 1 is the header)."""
        return self.row + 2

    def block(self, chunk: bytes, last: bool = False) -> None:
        """Parse whole lines (`chunk` ends with a newline)."""
        if b"\r" in chunk:
            chunk = chunk.replace(b"\r\n", b"\n")
        m = self.m
        lines = chunk.split(b"\n")[:-1]
        fast = (self.blank_line is None and not chunk.startswith(b"\n")
                and b"\n\n" not in chunk and bool(_ALLOWED[np.frombuffer(chunk, np.uint8)].all())
                and all(ln.count(b",") == m - 1 for ln in lines))
        if fast:
            cells = chunk[:-1].replace(b"\n", b",").split(b",")
            try:
                vals = np.fromiter(map(float, cells), dtype=float, count=len(cells))
            except ValueError:  # an empty cell, or not a number: line by line
                fast = False
        if not fast:
            for k, ln in enumerate(lines):
                self._line(ln, last and k == len(lines) - 1)
            return
        bad = np.flatnonzero(~np.isfinite(vals))
        for i in bad:
            r, j = divmod(int(i), m)
            c = cells[i].strip(b" ")
            if not (math.isnan(vals[i]) and c in _NANS):
                self._bad_cell(c, self.line + r, j)
        n = len(lines)
        self.data[:, self.row:self.row + n] = vals.reshape(n, m).T
        self.row += n

    def _line(self, ln: bytes, last: bool) -> None:
        line = self.line
        if not ln.strip(b" \t"):
            if self.blank_line is None:
                self.blank_line = line
            self.row += 1  # counted for line numbers; dropped at the end
            return
        if self.blank_line is not None:
            raise VtableError(f"{self.where}: line {self.blank_line} is empty but data "
                              f"follows on line {line}; only trailing empty lines are allowed")
        if b"\x00" in ln:
            raise VtableError(f"{self.where}: line {line}: binary data (NUL bytes), not a CSV "
                              "text file")
        try:
            ln.decode("utf-8")
        except UnicodeDecodeError:
            raise VtableError(f"{self.where}: line {line} is not UTF-8 text") from None
        for sep, name in ((b";", "';'"), (b"\t", "tabs")):
            if sep in ln:
                raise VtableError(f"{self.where}: line {line} is separated by {name}; "
                                  "expected comma-separated values")
        fields = ln.split(b",")
        if len(fields) != self.m:
            cut = " (the last line is cut short: an incomplete file?)" if last else ""
            raise VtableError(f"{self.where}: line {line} has {len(fields)} fields, the "
                              f"header {self.m}{cut}")
        out = self.data[:, self.row]
        for j, cell in enumerate(fields):
            c = cell.strip(b" ")
            if not c or c in _NANS:
                out[j] = np.nan
                continue
            if _NUMBER.fullmatch(c) is None:
                self._bad_cell(c, line, j)
            v = float(c)
            if math.isinf(v):
                self._bad_cell(c, line, j)
            out[j] = v
        self.row += 1

    def _bad_cell(self, c: bytes, line: int, j: int) -> None:
        text = c.decode("utf-8", errors="replace")
        where = f"{self.where}: line {line}, column {self.header[j]!r}"
        if _NUMBER.fullmatch(c) is not None:
            raise VtableError(f"{where}: {text[:30]} overflows a float (|value| > 1.8e308)")
        if text.strip().lower().lstrip("+-") in ("inf", "infinity"):
            raise VtableError(f"{where}: {text[:20]!r} is infinite; a missing sample is "
                              "written nan or left empty")
        raise VtableError(f"{where}: {text[:20]!r} is not a number (plain decimal or "
                          "scientific notation, nan or empty)")

    def rows(self) -> np.ndarray:
        end = self.blank_line - 2 if self.blank_line is not None else self.row
        return self.data[:, :end]


def _count_lines(fh: IO[bytes]) -> int:
    n, last = 0, b"\n"
    for block in iter(lambda: fh.read(BLOCK), b""):
        n += block.count(b"\n")
        last = block[-1:]
    return n + (last != b"\n")


def read_csv(path: Path) -> tuple[list[str], np.ndarray, list[str]]:
    """`parse_csv(path)`, or in a warm process's child the parse its warm process kept of
    the same bytes (`vtable.runs.parsed`)."""
    hit = parsed.kept(path)
    if hit is not None:
        return hit
    out = parse_csv(path)
    parsed.note(path, out[2])
    return out


def parse_csv(path: Path) -> tuple[list[str], np.ndarray, list[str]]:
    """Header and values of RUN.csv as a (columns x rows) array, NaN for missing samples,
    and notes (a last line without a line end).

    Where RUN.csv is absent and RUN.csv.gz is there (a run shipped compressed), that is
    read instead, and a note says so.

    Memory: the array plus one block of text (`BLOCK` bytes and its cells)."""
    gz = path.with_name(path.name + ".gz")
    try:
        fh: IO[bytes] = path.open("rb")
        notes: list[str] = []
    except FileNotFoundError:
        if not gz.is_file():
            raise VtableError(f"{path}: no such file") from None
        fh, notes = gzip.open(gz, "rb"), [f"{gz}: read compressed (gzip), as {path.name}"]
    except OSError as e:
        raise VtableError(f"{path}: cannot read: {e.strerror or type(e).__name__}") from None
    where = gz if notes else path
    with fh:
        try:
            header, data, more = _read_csv(fh, where)
        except (OSError, EOFError, zlib.error) as e:
            raise VtableError(f"{where}: cannot read: "
                              f"{getattr(e, 'strerror', None) or e or type(e).__name__}") \
                from None
    return header, data, notes + more


def _read_csv(fh: IO[bytes], path: Path) -> tuple[list[str], np.ndarray, list[str]]:
    first = fh.readline(HEADER_MAX)
    if len(first) == HEADER_MAX and not first.endswith(b"\n"):
        raise VtableError(f"{path}: line 1 is longer than {HEADER_MAX} bytes; not a run CSV")
    header = _header(first, path)
    start = fh.tell()
    rows = _count_lines(fh)
    fh.seek(start)
    rd = _Reader(path, header, rows)
    carry = b""
    for block in iter(lambda: fh.read(BLOCK), b""):
        block = carry + block
        cut = block.rfind(b"\n") + 1
        carry = block[cut:]
        if cut:
            rd.block(block[:cut])
    notes = []
    if carry:
        line = rd.line
        rd.block(carry + b"\n", last=True)
        if carry.strip(b" \t\r"):
            notes.append(f"{path}: the last line ({line}) has no line end; if the file was cut "
                         "short, its last sample may be incomplete")
    data = rd.rows()
    if data.shape[1] < 2:
        raise VtableError(f"{path}: needs at least two samples, got {data.shape[1]}")
    return header, data, notes


