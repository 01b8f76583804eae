"""Reading, validating and writing runs (CSV + TOML, and HDF5 with the same content).

Errors are one line naming the file, the line, the column or the key and what was
expected. Things the format allows but a user should know about — unknown keys or
channels (kept), missing samples (kept as NaN, counted per channel), constant channels,
time stamps put on a uniform grid, a run without [specimen] — are collected in
`Run.reports`.

The CSV is read in blocks straight into one preallocated float64 array (a row per
column), so reading costs about the size of the samples in memory, not of the text.
A cell is plain ASCII decimal or scientific notation, ``nan`` (also ``NaN``, ``NAN``) or
empty for a missing sample; Python's other float spellings (``1_000``, full-width or
Arabic-Indic digits, ``inf``, ``infinity``) are refused.
"""

from __future__ import annotations

import csv
import io
import math
import re
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

import numpy as np

from vtable import fileio
from vtable import units as un
from vtable.errors import VtableError
from vtable.runs.format import FORMAT, check_control, check_units, command_from_dict, dumps_toml
from vtable.runs.model import COMMAND_CHANNELS, FORMAT_UNITS, TOP_KEYS, Run

#: a time step is uniform when within this fraction of the median step (spec)
UNIFORM_TOL = 1e-3
#: time stamps closer than this fraction of a step to the fitted grid are kept as they are
#: (float rounding of a uniform grid); otherwise the grid t0 + k·dt replaces them
GRID_TOL = 1e-9
BLOCK = 1 << 20  # bytes read at a time (the reader needs about 10 blocks beyond the samples)
HEADER_MAX = 1 << 20

_BOM = b"\xef\xbb\xbf"
_ALLOWED = np.zeros(256, dtype=bool)
_ALLOWED[np.frombuffer(b"0123456789+-.eEnaNA ,\n", dtype=np.uint8)] = True
_NUMBER = re.compile(rb"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NANS = {s + n for s in (b"", b"+", b"-") for n in (b"nan", b"NaN", b"NAN")}


# ---- paths ----------------------------------------------------------------------------
def _stem(path: str | Path) -> Path:
    """The common stem of RUN.toml and RUN.csv: the path without a .toml or .csv suffix
    (other dots are part of the stem: p10_scl0.1, run.txt)."""
    p = Path(path)
    if p.suffix.lower() in (".toml", ".csv"):
        return p.with_name(p.name[: -len(p.suffix)])
    return p


def _paths(path: str | Path) -> tuple[Path, Path]:
    stem = _stem(path)
    return stem.with_name(stem.name + ".toml"), stem.with_name(stem.name + ".csv")


def _read_text(p: Path) -> str:
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


# ---- RUN.toml -------------------------------------------------------------------------
def read_meta(toml_path: Path) -> tuple[dict[str, Any], list[str]]:
    """Parse and check RUN.toml; returns the table and the reports (unknown keys, ...)."""
    text = _read_text(toml_path).removeprefix("\ufeff")
    try:
        meta = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise VtableError(f"{toml_path}: malformed TOML: {e}") from None
    reports: list[str] = []
    check_meta(meta, str(toml_path), toml_path.parent, reports)
    return meta, reports


def check_meta(meta: dict[str, Any], where: str, folder: Path | None,
               reports: list[str]) -> None:
    """Every table of a run's metadata, checked; notes go to `reports`."""
    from vtable.params.specimen import specimen_from_dict
    from vtable.runs.table import table_from_dict

    if meta.get("format") != FORMAT:
        raise VtableError(f"{where}: key 'format' must be {FORMAT!r}, got "
                          f"{meta.get('format')!r:.60}")
    if "title" in meta and not isinstance(meta["title"], str):
        raise VtableError(f"{where}: key 'title' must be a string, got {meta['title']!r:.60}")
    reports += [f"{where}: unknown key {k!r} (kept, not used)" for k in meta
                if k not in TOP_KEYS]
    for k in ("table", "control", "specimen", "command", "units"):
        if k in meta and not isinstance(meta[k], dict):
            raise VtableError(f"{where}: [{k}] must be a table, got {type(meta[k]).__name__}")
    if "table" in meta:
        reports += table_from_dict(meta["table"], f"{where} [table]").notes
    else:
        reports.append(f"{where}: no [table]: the table the run was made on is not named")
    if "control" in meta:
        reports += check_control(meta["control"], f"{where} [control]")
    if "specimen" in meta:
        specimen_from_dict(meta["specimen"], f"{where} [specimen]")
    else:
        reports.append(f"{where}: no [specimen]: treated as a bare table")
    if "command" in meta:
        reports += command_from_dict(meta["command"], f"{where} [command]", folder).notes
    check_units(meta.get("units", {}), f"{where}: [units]")


def _check_against_rate(meta: dict[str, Any], fs: float, where: str,
                        folder: Path | None) -> None:
    """What the TOML says must be resolvable at the run's sampling rate: specimen
    frequencies and the command's band below the Nyquist frequency."""
    from vtable.analytic.structure import specimen_frequencies
    from vtable.params.specimen import specimen_from_dict

    nyq = fs / 2
    if "specimen" in meta:
        spec = specimen_from_dict(meta["specimen"], f"{where} [specimen]")
        given = meta["specimen"] if isinstance(meta["specimen"], dict) else {}
        key = next((k for k in ("frequency_hz", "frequencies_hz", "stiffness_kip_per_in",
                                "stiffnesses_kip_per_in") if k in given), "frequency")
        for f in specimen_frequencies(spec):
            if f >= nyq:
                raise VtableError(f"{where} [specimen].{key}: {f:.6g} Hz is at or above "
                                  f"the run's Nyquist frequency {nyq:.6g} Hz (sampled at "
                                  f"{fs:.6g} Hz)")
    if "command" in meta:
        cmd = command_from_dict(meta["command"], f"{where} [command]", folder)
        cmd.check_rate(fs, f"{where} [command]")


# ---- RUN.csv --------------------------------------------------------------------------
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
    """Header and values of RUN.csv as a (columns x rows) array, NaN for missing samples,
    and notes (a last line without a line end).

    Memory: the array plus one block of text (`BLOCK` bytes and its cells)."""
    try:
        fh = path.open("rb")
    except FileNotFoundError:
        raise VtableError(f"{path}: no such file") from None
    except OSError as e:
        raise VtableError(f"{path}: cannot read: {e.strerror or type(e).__name__}") from None
    with fh:
        try:
            return _read_csv(fh, path)
        except OSError as e:
            raise VtableError(f"{path}: cannot read: {e.strerror or type(e).__name__}") \
                from None


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


def parse_csv(text: str, where: Path) -> tuple[list[str], np.ndarray, dict[str, int]]:
    """Header, values (rows x columns, NaN for `nan` or empty) and missing counts of a
    run CSV given as text (the file reader is `read_csv`)."""
    fh = io.BytesIO(text.encode("utf-8"))
    header, data, _ = _read_csv(fh, Path(where))
    missing = {h: int(np.isnan(data[j]).sum()) for j, h in enumerate(header)}
    return header, data.T, missing


def check_time(t: np.ndarray, where: Path | str, first_line: int = 2,
               what: str = "line") -> tuple[np.ndarray, float]:
    """Check time stamps (s) and return the time base and the largest deviation of the
    stamps from it.

    Stamps must increase; a step counts as uniform within `UNIFORM_TOL` of the median
    step (relative, the spec's rule), or when the stamps' printed precision explains the
    scatter (`_rounded_grid`: 7 significant digits at t = 12.34567 s shift a 256 Hz step
    by 2.6e-3 of itself, and lab exports print so); a larger irregularity (a lost sample,
    a restart) is an error naming the line. The time base is the least-squares grid
    t0 + k·dt through the stamps, or the stamps themselves when they are that grid to
    `GRID_TOL` of a step (float rounding), so runs round-trip exactly.
    """
    def at(i: int) -> str:
        return f"{what} {i + first_line}"

    nan = np.flatnonzero(np.isnan(t))
    if len(nan):
        raise VtableError(f"{where}: {at(int(nan[0]))}: column 'time' has missing samples")
    steps = np.diff(t)
    back = np.flatnonzero(~(steps > 0))
    if len(back):
        i = int(back[0])
        how = "repeats" if steps[i] == 0 else "goes back from"
        raise VtableError(f"{where}: {at(i + 1)}: time {t[i + 1]:.9g} s {how} "
                          f"{t[i]:.9g} s ({at(i)}); time stamps must increase")
    med = float(np.median(steps))
    n = len(t)
    k = np.arange(n, dtype=float)
    kc = k - (n - 1) / 2
    t_mean = float(np.mean(t))
    dt = float(np.dot(kc, t - t_mean) / np.dot(kc, kc))
    grid = t_mean + kc * dt
    off = np.flatnonzero(np.abs(steps - med) > UNIFORM_TOL * med)
    if len(off) and not _rounded_grid(t, grid, dt):
        dev = np.abs(steps[off] - med)
        i = int(off[np.argmax(dev >= 0.5 * dev.max())])  # the first large irregularity
        raise VtableError(f"{where}: column 'time' is not uniform: step {steps[i]:.9g} s at "
                          f"{at(i + 1)} vs median {med:.9g} s (a lost sample or a restart?)")
    dev = float(np.max(np.abs(t - grid)))
    if dev <= GRID_TOL * dt:
        return t, dev
    return grid, dev


def _rounded_grid(t: np.ndarray, grid: np.ndarray, dt: float) -> bool:
    """Whether stamps whose steps scatter beyond the spec's tolerance are a uniform grid
    printed with limited precision: every stamp within its printing rounding
    (`printed_quantum`) of the least-squares grid, that rounding finer than a tenth of a
    step (so a lost sample, half a step off the grid, is never explained away)."""
    q = printed_quantum(t)
    if not q.any() or q.max() > 0.1 * dt:
        return False
    return bool(np.all(np.abs(t - grid) <= q + UNIFORM_TOL * dt))


def printed_quantum(t: np.ndarray, most: int = 17) -> np.ndarray:
    """Half-width of the rounding each stamp may carry from being printed: the file's
    significant digits S are the most any stamp needs (up to `most`); a stamp at t was
    then rounded to 10^(⌊log₁₀|t|⌋ − S + 1). Files printed with fewer than 6 significant
    digits are taken as exact (stamps like 0.005 need no more), full-precision files
    (S ≥ 15) too."""
    q = np.zeros(len(t))
    nz = t != 0
    if not nz.any():
        return q
    tz = np.abs(t[nz])
    mag = np.floor(np.log10(tz))
    sig = np.full(len(tz), most)
    left = np.ones(len(tz), dtype=bool)
    for d in range(1, most + 1):
        if not left.any():
            break
        unit = 10.0 ** (mag[left] - d + 1)
        x = tz[left] / unit
        hit = np.abs(x - np.round(x)) <= 1e-6 * np.maximum(x, 1.0) * 1e-3
        idx = np.flatnonzero(left)[hit]
        sig[idx] = d
        left[idx] = False
    digits = int(sig.max())
    if digits < 6 or digits >= 15:
        return q
    q[nz] = 0.5 * 10.0 ** (mag - digits + 1)
    return q


def _locate(first_line: int, what: str) -> Callable[[int], str]:
    return lambda i: f"{what} {i + first_line}"


def _check_channel(name: str, v: np.ndarray, unit: str, where: Path | str,
                   at: Callable[[int], str]) -> None:
    """Values (in `unit`, before conversion) of plausible magnitude for the channel's
    dimension (`units.PLAUSIBLE_MAX`); finite or NaN."""
    dim = un.dimension(unit)
    limit = un.from_si(un.PLAUSIBLE_MAX[dim], unit)
    a = np.abs(v)
    peak = np.fmax.reduce(a) if len(a) else 0.0
    if peak > limit:  # False for NaN
        i = int(np.flatnonzero(a > limit)[0])
        raise VtableError(f"{where}: {at(i)}, column {name!r}: {v[i]:.6g} {unit} is not a "
                          f"plausible {un.noun(dim)} (the limit is {limit:.3g} {unit})")


def _channel_reports(name: str, v: np.ndarray, unit: str, where: Path | str,
                     at: Callable[[int], str]) -> list[str]:
    out = []
    nan = np.isnan(v)
    n = int(nan.sum())
    if n == len(v):
        return [f"{where}: column {name!r} has no samples (all {n} missing samples)"]
    if n:
        out.append(f"{where}: column {name!r} has {n} missing samples of {len(v)} (first at "
                   f"{at(int(np.argmax(nan)))}); kept as NaN, not filled: what needs this "
                   "channel refuses it")
    lo, hi = np.fmin.reduce(v), np.fmax.reduce(v)
    if lo == hi:
        role = "it drives nothing" if name in COMMAND_CHANNELS else "it carries no signal"
        out.append(f"{where}: column {name!r} is constant ({un.from_si(lo, unit):g} {unit}): "
                   f"{role}")
    return out


def _assemble(name: str, header: list[str], data: np.ndarray, meta: dict[str, Any],
              reports: list[str], toml_where: str, data_where: Path | str, source: Path,
              at: Callable[[int], str], first_line: int, what: str) -> Run:
    """Run from checked metadata and raw columns (file units): time base, units to SI,
    plausibility, reports, the checks that need the sampling rate."""
    overrides = meta.get("units", {})
    t_unit = overrides.get("time", "s")
    _check_channel("time", data[0], t_unit, data_where, at)
    t = data[0] * un.factor(t_unit) if t_unit != "s" else data[0]
    time, dev = check_time(t, data_where, first_line, what)
    if time is not t:
        dt = (time[-1] - time[0]) / (len(time) - 1)
        reports.append(f"{data_where}: time stamps deviate from a uniform grid by up to "
                       f"{dev:.3g} s ({dev / dt:.3%} of the {dt:.9g} s step); the uniform "
                       "grid t0 + k·dt is used")
    elif t_unit != "s":
        time = t.copy()
    channels, units, extra = {}, {}, []
    for j, h in enumerate(header[1:], start=1):
        unit = overrides.get(h, FORMAT_UNITS.get(h))
        if h not in FORMAT_UNITS:
            extra.append(h)
        units[h] = unit or "1"
        v = data[j]
        _check_channel(h, v, units[h], data_where, at)
        f = un.factor(units[h])
        if f != 1.0:
            v *= f  # in place: the array is the reader's own
        channels[h] = v
        reports += _channel_reports(h, v, units[h], data_where, at)
    if extra:
        no_unit = [h for h in extra if h not in overrides]
        reports.append(f"{data_where}: {len(extra)} column(s) not in the format, kept: "
                       + ", ".join(extra[:6]) + (", ..." if len(extra) > 6 else "")
                       + (f" ({len(no_unit)} without a unit)" if no_unit else ""))
    for h in overrides:
        if h not in channels and h != "time":
            reports.append(f"{toml_where}: [units] names {h!r}, which is not a column (kept, "
                           "not used)")
    if "h_span" not in channels and not (isinstance(meta.get("command"), dict)
                                         and "drive_file" in meta["command"]):
        reports.append(f"{toml_where}: no h_span column and no [command] drive_file: the "
                       "command the table played is not known")
    fs = (len(time) - 1) / (time[-1] - time[0])
    _check_against_rate(meta, fs, toml_where, source.parent)
    missing = {h: int(np.isnan(v).sum()) for h, v in channels.items()}
    run = Run(name=name, time=time, channels=channels, units=units, meta=meta, source=source,
              missing={h: n for h, n in missing.items() if n}, extra=extra, reports=reports)
    if isinstance(meta.get("command"), dict) and "drive_file" in meta["command"]:
        from vtable.runs.drive import apply_drive

        run = apply_drive(run, toml_where)  # the command from the drive file
    return run


def read_run(path: str | Path) -> Run:
    """Read RUN.toml + RUN.csv (give either file or the common stem).

    Parameters
    ----------
    path
        ``RUN.toml``, ``RUN.csv`` or ``RUN``; a stem keeps its dots (``p10_scl0.1``).

    Returns
    -------
    Run
        Channels in SI; `reports` lists what the reader noticed and kept.

    Raises
    ------
    VtableError
        One line naming the file and the line, column or key.
    """
    toml_path, csv_path = _paths(path)
    meta, reports = read_meta(toml_path)
    header, data, notes = read_csv(csv_path)
    reports += notes
    return _assemble(str(_stem(toml_path)), header, data, meta, reports, str(toml_path),
                     csv_path, toml_path, _locate(2, "line"), 2, "line")


# ---- writing --------------------------------------------------------------------------
def _file_meta(run: Run) -> dict[str, Any]:
    meta = {k: v for k, v in run.meta.items() if k != "format"}
    overrides = {h: u for h, u in run.units.items() if h in run.channels
                 and FORMAT_UNITS.get(h) != u and not (h not in FORMAT_UNITS and u == "1")}
    if overrides:
        meta["units"] = overrides
    else:
        meta.pop("units", None)
    return {"format": FORMAT, **meta}


def _check_writable(run: Run) -> list[str]:
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
        if u not in un.UNITS:
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
    toml_path, csv_path = _paths(path)
    names = _check_writable(run)
    toml_text = dumps_toml(_file_meta(run))
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


def write_hdf5(run: Run, path: str | Path) -> Path:
    """The same content in one HDF5 file: /time (s), /channels/<name> (file units), the
    TOML metadata (with every channel's unit in [units]) as the attribute 'toml', the
    channel order as the attribute 'order'. Written to a temporary file and renamed."""
    import h5py

    p = Path(path)
    names = _check_writable(run)
    meta = {**_file_meta(run), "units": {h: run.units.get(h, "1") for h in names}}
    text = dumps_toml(meta)
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
    import h5py

    p = Path(path)
    if not p.is_file():
        raise VtableError(f"{p}: no such file" if not p.exists() else f"{p}: not a file")
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
    reports: list[str] = []
    check_meta(meta, str(p), p.parent, reports)
    units = meta.pop("units", {})
    override = {h: u for h, u in units.items() if FORMAT_UNITS.get(h) != u and u != "1"}
    if override:
        meta["units"] = override
    if n < 2:
        raise VtableError(f"{p}: needs at least two samples, got {n}")
    run_meta = {**meta, "units": {**units, **{h: units.get(h, "1") for h in order}}}
    run = _assemble(str(_stem_h5(p)), ["time", *order], data, run_meta, reports, str(p), p, p,
                    _locate(0, "sample"), 0, "sample")
    run.meta = meta
    return run


def _stem_h5(p: Path) -> Path:
    return p.with_name(p.name[: -len(p.suffix)]) if p.suffix else p


def _dataset(ds: Any, name: str, p: Path, n: int | None) -> int:
    """Check a dataset is 1-D, numeric and (for a channel) as long as /time; its length."""
    import h5py

    if not isinstance(ds, h5py.Dataset) or ds.ndim != 1 or ds.dtype.kind not in "fiu":
        raise VtableError(f"{p}: {name!r} must be a one-dimensional numeric dataset")
    if n is not None and ds.shape[0] != n:
        raise VtableError(f"{p}: channel {name!r} has {ds.shape[0]} samples, /time {n}")
    return int(ds.shape[0])


def read_any(path: str | Path) -> Run:
    """A run from RUN.toml/RUN.csv or an HDF5 file (.h5, .hdf5)."""
    p = Path(path)
    return read_hdf5(p) if p.suffix.lower() in (".h5", ".hdf5") else read_run(p)


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
