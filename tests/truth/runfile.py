"""Run files in the interchange format (docs/run-format.md), written by the
truth's own code: RUN.csv (time + channels) and RUN.toml, optionally a drive file.

EERC runs use the format's units (in, g, kip, in/s, rad, rad/s²); LNEC runs are written
in SI and say so in [units]. Sensor noise is white Gaussian, `noise` x the channel's RMS,
independent per sensor and seeded; the command h_span is clean. Files are written to a
temporary name and renamed into place.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np

from . import constants as c
from .commands import Command, earthquake_command, random_command
from .errors import TruthError
from .simulate import Result, simulate
from .specimens import Specimen
from .tables import Table

FORMAT = "vtable-run/1"
#: SI -> format unit divisor, per channel family
EERC_UNITS = {"disp": ("in", c.INCH), "vel": ("in/s", c.INCH), "acc": ("g", c.G),
              "force": ("kip", c.KIP), "rad": ("rad", 1.0), "rad/s2": ("rad/s2", 1.0)}
SI_UNITS = {"disp": ("m", 1.0), "vel": ("m/s", 1.0), "acc": ("m/s2", 1.0),
            "force": ("N", 1.0), "rad": ("rad", 1.0), "rad/s2": ("rad/s2", 1.0)}
DRIVE_UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": c.INCH}
#: the control knobs of Table B.5's standard settings (Table B.1: gain 9, ΔP 1.5, rate 5)
EERC_STANDARD_CONTROL = {"horizontal": {"gain": 9.0, "delta_p": 1.5, "rate": 5.0}}


FAMILY = {"h_span": "disp", "avg_hdisp": "disp", "h_vel": "vel", "avg_hacc": "acc",
          "pitch_acc": "rad/s2", "pitch_disp": "rad", "acc_n_ne": "acc", "acc_n_nw": "acc",
          "pot_n_sw": "disp", "pot_n_se": "disp",
          **{f"h{i}_disp": "disp" for i in (1, 2, 3)},
          **{f"h{i}_force": "force" for i in (1, 2, 3)},
          **{f"v{i}_force": "force" for i in (1, 2, 3, 4)},
          **{f"p{i}_stab": "force" for i in (1, 2, 3, 4)}}


FLOOR_FAMILY = {"_acc": "acc", "_disp": "disp", "_drift": "disp", "_shear": "force"}


def family(name: str) -> str:
    """The unit family of a channel (floorK_acc, floorK_disp, floorK_drift and floorK_shear
    included)."""
    if name in FAMILY:
        return FAMILY[name]
    if name.startswith("floor"):
        for suffix, fam in FLOOR_FAMILY.items():
            if name.endswith(suffix):
                return fam
    raise TruthError(f"write_run: no unit for channel {name!r}")


ORDER = ("h_span", "avg_hdisp", "h1_disp", "h2_disp", "h3_disp", "h_vel", "avg_hacc",
         "h1_force", "h2_force", "h3_force", "pitch_acc", "pitch_disp", "v1_force",
         "v2_force", "v3_force", "v4_force", "p1_stab", "p2_stab", "p3_stab", "p4_stab",
         "acc_n_ne", "acc_n_nw", "pot_n_sw", "pot_n_se")


def _atomic_write(path: Path, text: str) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except OSError as e:
        raise TruthError(f"{path}: cannot write: {e.strerror}") from None


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, int | np.integer):
        return str(int(v))
    if isinstance(v, float | np.floating):
        return repr(float(v))
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TruthError(f"write_run: cannot write {type(v).__name__} to TOML")


def toml_text(d: dict, inline: tuple[str, ...] = ("control",), prefix: str = "") -> str:
    """TOML for a dict of scalars, lists and tables; a table inside a table becomes its own
    [a.b] section, except inside the top-level sections named in `inline` (written as
    inline tables, as [control] is)."""
    lines = []
    for k, v in d.items():
        if not isinstance(v, dict) or (prefix and prefix.split(".")[0] in inline):
            lines.append(f"{k} = {_toml_value(v)}")
    text = "\n".join(lines) + ("\n" if lines else "")
    for k, v in d.items():
        if isinstance(v, dict) and not (prefix and prefix.split(".")[0] in inline):
            name = f"{prefix}.{k}" if prefix else k
            text += f"\n[{name}]\n" + toml_text(v, inline, name)
    return text


def table_declared(table: Table) -> dict:
    """The run's [table]: the preset, and what issue 18's format adds when the truth has it:
    force_measured (in [table.horizontal], as the format places it), and the controller
    when it is not the preset's own ([table.controller]; on the EERC table also the valve
    flow gain per actuator it needs, in [table.horizontal])."""
    out: dict = {"preset": table.preset}
    horizontal: dict = {}
    if table.force_measured is not None:  # the spec's [table.horizontal] key
        horizontal["force_measured"] = table.force_measured
    if table.declare_controller and table.law is not None:
        if table.preset == "eerc":
            horizontal["valve_flow_gain_m3_per_s_v"] = table.valve_gain / table.actuators
        out["controller"] = table.law.declared()
    if horizontal:
        out["horizontal"] = horizontal
    return out


def _noisy(res: Result, noise: float, seed: int) -> dict[str, np.ndarray]:
    """Each channel gets its own noise (a separate sensor); avg_hdisp is the average of the
    actuators' noisy displacements, as the controller forms it."""
    if not 0 <= noise < 1:
        raise TruthError(f"write_run: noise must be a fraction in [0, 1), got {noise!r}")
    rng = np.random.default_rng(seed)
    out = {}
    for k, v in res.channels.items():
        if k in ("h_span", "avg_hdisp"):
            out[k] = v.copy()
            continue
        rms = float(np.sqrt(np.mean(v**2)))
        out[k] = v + noise * rms * rng.standard_normal(len(v))
    hs = [k for k in ("h1_disp", "h2_disp", "h3_disp") if k in out]
    na = res.table.actuators
    if na > 1:
        out["avg_hdisp"] = np.mean([out[k] for k in hs], axis=0)
    else:
        v = res.channels["avg_hdisp"]
        out["avg_hdisp"] = v + noise * float(np.sqrt(np.mean(v**2))) * rng.standard_normal(
            len(v))
        for k in hs:
            del out[k]  # one actuator: its displacement is avg_hdisp
    return out


def write_run(path: str | Path, res: Result, declared: Specimen | dict, noise: float = 0.02,
              seed: int = 0, drive: dict | None = None, title: str | None = None,
              channels: list[str] | None = None) -> list[Path]:
    """Write RUN.csv + RUN.toml (and the drive file in drive-file mode).

    declared: what the lab says it tested ([specimen]); a Specimen or the table itself.
    drive: None (h_span recorded) or {"unit": "mm", "scale": 1.0, "offset_samples": 5,
    "offset": "auto" | "number"}: no h_span column; the command divided by `scale` goes to
    STEM_drive.csv (time, displacement in `unit`); the acquisition starts offset_samples
    late, so drive_offset_s = offset_samples/fs (written, or "auto").
    channels: the channels to write (default: all the run has; h_span is implied unless
    in drive-file mode).
    Returns the paths written (toml, csv[, drive])."""
    stem = Path(path)
    if stem.suffix in (".toml", ".csv"):
        stem = stem.with_suffix("")
    si = res.table.preset != "eerc"
    units = SI_UNITS if si else EERC_UNITS
    chans = _noisy(res, noise, seed)
    names = [k for k in ORDER if k in chans] + [k for k in chans if k not in ORDER]
    if channels is not None:
        missing = [k for k in channels if k not in chans]
        if missing:
            raise TruthError(f"write_run: the run has no channel(s) {missing}; it has "
                             f"{', '.join(names)}")
        names = [k for k in names if k in channels or k == "h_span"]
    t = res.t
    cmd_table = dict(res.command.table)
    written = []
    start = 0
    if drive is not None:
        unknown = set(drive) - {"unit", "scale", "offset_samples", "offset"}
        if unknown:
            raise TruthError(f"write_run: unknown drive key(s) {sorted(unknown)}")
        unit = drive.get("unit", "mm")
        if unit not in DRIVE_UNITS:
            raise TruthError(f"write_run: drive unit {unit!r} not one of {list(DRIVE_UNITS)}")
        scale = float(drive.get("scale", 1.0))
        start = int(drive.get("offset_samples", 0))
        if not 0 <= start < len(t) // 2:
            raise TruthError(f"write_run: offset_samples must be in [0, {len(t) // 2}), got "
                             f"{start}")
        dpath = stem.parent / f"{stem.name}_drive.csv"
        x = res.channels["h_span"] / DRIVE_UNITS[unit] / scale
        _atomic_write(dpath, "time,displacement\n" + "".join(
            f"{float(a)!r},{b:.9g}\n" for a, b in zip(t, x, strict=True)))
        names.remove("h_span")
        mode = drive.get("offset", "number")
        cmd_table.update({"drive_file": dpath.name, "drive_unit": unit, "drive_scale": scale,
                          "drive_offset_s": "auto" if mode == "auto" else start / res.fs})
        written.append(dpath)
    cols = [units[family(k)] for k in names]
    ta = t[: len(t) - start]  # the acquisition clock starts at 0 when it starts
    rows = [",".join(["time", *names]) + "\n"]
    data = np.column_stack([chans[k][start:] / f for k, (_, f) in zip(names, cols,
                                                                          strict=True)])
    for ti, row in zip(ta, data, strict=True):
        rows.append(repr(float(ti)) + "," + ",".join(f"{v:.9g}" for v in row) + "\n")
    meta: dict = {"format": FORMAT,
                  "title": title or f"truth: {res.command.title} on {res.table.preset}"}
    meta["table"] = table_declared(res.table)
    if res.table.preset == "eerc" and res.table.physical and res.table.law is None:
        meta["control"] = EERC_STANDARD_CONTROL
    meta["specimen"] = declared.declared() if isinstance(declared, Specimen) else dict(declared)
    meta["command"] = cmd_table
    if si:
        meta["units"] = {k: u for k, (u, _) in zip(names, cols, strict=True)}
    tpath, cpath = stem.with_suffix(".toml"), stem.with_suffix(".csv")
    _atomic_write(cpath, "".join(rows))
    _atomic_write(tpath, toml_text(meta))
    return [tpath, cpath, *written]


def campaign(folder: str | Path, table: Table, spec: Specimen, declared: Specimen | dict,
             fs: float = 256.0, noise: float = 0.02, seed: int = 0,
             spans_in: tuple[float, float] = (0.1, 1.0), duration_s: float = 40.0,
             band_hz: tuple[float, float] = (0.0, 25.0), quake_peak_in: float = 3.0,
             record: str = "elcentro", drive: dict | None = None) -> list[Path]:
    """The usual three runs of one configuration: band-limited random at two peak spans
    and an earthquake. Returns the three RUN.toml paths."""
    folder = Path(folder)
    cmds: list[tuple[str, Command]] = [
        (f"random_{i}", random_command(duration_s, band_hz, peak_in=span, seed=seed + i))
        for i, span in enumerate(spans_in)]
    cmds.append(("earthquake", earthquake_command(record, peak_in=quake_peak_in,
                                                  seed=seed + 7)))
    out = []
    for k, (name, cmd) in enumerate(cmds):
        res = simulate(table, spec, cmd, fs=fs)
        out.append(write_run(folder / name, res, declared, noise=noise, seed=seed + 100 + k,
                             drive=drive)[0])
    return out
