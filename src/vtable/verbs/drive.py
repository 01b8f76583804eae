"""`vtable drive`: the drive that makes the specimen feel a target, from a model calibrated
on the lab's runs (`vtable.drive`), and the lab loop (`--update`)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from vtable import units
from vtable.diagnose.calibration import Calibration
from vtable.diagnose.model import TableModel
from vtable.drive import DRIVE_FS, DriveResult, compensate, read_target
from vtable.drive.target import Target
from vtable.errors import VtableError
from vtable.fileio import write_text
from vtable.ident.drive import align
from vtable.ident.structure import effective_height
from vtable.runs import campaign, write_run
from vtable.runs.model import FORMAT_UNITS, Run
from vtable.verbs.effects import effect_names


def effects_from(path: str) -> list[str]:
    """The final effects of a diagnosis JSON (`vtable diagnose --json`)."""
    try:
        d = json.loads(Path(path).read_text())
    except (OSError, ValueError) as e:
        raise VtableError(f"{path}: not a diagnosis JSON ({e})") from None
    if not isinstance(d, dict) or "final_effects" not in d:
        raise VtableError(f"{path}: no 'final_effects': not a diagnosis JSON "
                          "(vtable diagnose --json)")
    return effect_names(",".join(d["final_effects"]))


def drive(paths: Sequence[str], target: str, out: str, target_unit: str = "in",
          objective: str = "effective", with_: Sequence[str] = (), from_: str | None = None,
          calibrate: str = "", regularisation: float = 0.05, cap: float = 4.0,
          update: Sequence[str] = (), fmt: str = "csv", png: str | None = None,
          target_peak: float | None = None) -> DriveResult:
    """Calibrate the model of the runs (the base and the effects `with_`, or a diagnosis's
    final effects from `from_`), compute the drive for `target` and write it to `out`
    (STEM.csv + STEM.toml: the drive as h_span with the model's predicted channels;
    STEM.txt, two columns, with `fmt` "txt"). `update`: runs the lab measured with the
    previous drive; the model is recalibrated with them and the drive corrected from the
    last one's measured error (`compensate(measured=...)`)."""
    effects = list(with_) + (effects_from(from_) if from_ else [])
    runs = [align(r) for r in campaign(list(paths))]
    measured_runs = [align(r) for r in campaign(list(update))] if update else []
    tgt = read_target(target, target_unit, peak=target_peak)
    model = TableModel(list(dict.fromkeys(effects)),
                       calibration=Calibration.parse(calibrate)).fit(runs + measured_runs)
    h = effective_height(runs[0])
    measured = None
    if measured_runs:
        measured = _measured(measured_runs[-1], tgt, h, objective)
    res = compensate(model, tgt, h, objective, regularisation, cap, measured=measured)
    res.notes.append(f"model: the base calibrated on {len(runs)} run(s)"
                     + (f" and {len(measured_runs)} lab run(s) of a previous drive"
                        if measured_runs else "")
                     + (f", with {', '.join(model.effects)}" if model.effects else ""))
    res.notes.append(f"lab runs used by this drive: {len(measured_runs)}")
    _write(res, runs[0], out, fmt)
    if png:
        res.plot(png)
    return res


def _measured(run: Run, tgt: Target, h: float, objective: str
              ) -> tuple[np.ndarray, np.ndarray]:
    """(the drive played, the objective motion measured) of a lab run, at the target's
    rate and length."""
    t = tgt.t
    for c in ("h_span", "avg_hdisp"):
        if not run.has(c):
            raise VtableError(f"{run.name}: no channel {c!r}: a run measured with the "
                              "previous drive needs it for --update")
    tr = run.time - run.time[0]
    if tr[-1] < t[-1] - 1e-6:
        raise VtableError(f"{run.name}: {tr[-1]:.2f} s, shorter than the target's "
                          f"{t[-1]:.2f} s: play the whole drive")
    d = np.interp(t, tr, run.channels["h_span"])
    y = np.interp(t, tr, run.channels["avg_hdisp"])
    if objective == "effective" and run.has("pitch_disp"):
        y = y + h * np.interp(t, tr, run.channels["pitch_disp"])
    return d, y


def _write(res: DriveResult, template: Run, out: str, fmt: str) -> None:
    """STEM.csv + STEM.toml: a run holding the drive (h_span) and the model's predicted
    channels, declared as the campaign is; STEM.txt (time, drive in in) with fmt txt."""
    if fmt not in ("csv", "txt"):
        raise VtableError(f"--format: expected csv or txt, got {fmt!r}")
    t = res.target.t
    ch = {"h_span": res.drive.drive}
    for k in ("avg_hdisp", "avg_hacc", "h_vel", "pitch_disp", "pitch_acc", "acc_n_ne",
              "pot_n_sw", "h1_force"):
        if k in res.drive.channels:
            ch[k] = np.asarray(res.drive.channels[k])[:len(t)]
    meta = {k: v for k, v in template.meta.items() if k in ("format", "table", "control",
                                                             "specimen")}
    meta["title"] = (f"vtable drive for {res.target.name} ({res.objective} motion): the "
                     "drive as h_span, the calibrated model's predicted channels")
    file_units = {k: template.units.get(k, FORMAT_UNITS.get(k, "1")) for k in ch}
    run = Run(Path(out).name, t, ch, file_units, meta)
    res.files += list(write_run(run, out))
    if fmt == "txt":
        rows = "\n".join(f"{a:.6f} {b:.8g}" for a, b in
                         zip(t, units.from_si(res.drive.drive, "in"), strict=True))
        res.files.append(write_text(Path(f"{out}.txt"),
                                    f"# time (s), drive (in) at {DRIVE_FS:g} Hz\n{rows}\n"))
