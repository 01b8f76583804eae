"""`vtable drive`: the drive that makes the specimen feel a target, from a model calibrated
on the lab's runs (`vtable.drive`), and the lab loop (`--update`)."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from vtable import units
from vtable.diagnose.calibration import Calibration
from vtable.diagnose.model import TableModel
from vtable.diagnose.reading import OTHER, undeclared
from vtable.drive import DRIVE_FS, DriveResult, compensate, read_target
from vtable.drive.compensate import BAND_HZ, CAP, REGULARISATION
from vtable.drive.target import REST_S, Target
from vtable.errors import VtableError
from vtable.fileio import write_text
from vtable.ident.drive import align
from vtable.ident.structure import effective_height
from vtable.runs import campaign, write_run
from vtable.runs.model import FORMAT_UNITS, Run
from vtable.verbs.effects import effect_names


def _diagnosis_json(path: str) -> dict:
    try:
        d = json.loads(Path(path).read_text())
    except (OSError, ValueError) as e:
        raise VtableError(f"{path}: not a diagnosis JSON ({e})") from None
    if not isinstance(d, dict) or "final_effects" not in d:
        raise VtableError(f"{path}: no 'final_effects': not a diagnosis JSON "
                          "(vtable diagnose --json)")
    return d


def effects_from(path: str) -> list[str]:
    """The final effects of a diagnosis JSON (`vtable diagnose --json`)."""
    return effect_names(",".join(_diagnosis_json(path)["final_effects"]))


def diagnosis_values(path: str) -> dict[str, float] | None:
    """Every calibrated parameter of a diagnosis's final model, "owner.param" -> value
    (its `base` fitted values and its `final_params`); None when the JSON does not hold
    them (a diagnosis written by another tool to the spec's minimum)."""
    d = _diagnosis_json(path)
    base, params = d.get("base"), d.get("final_params")
    if not isinstance(base, dict) or not isinstance(params, dict):
        return None
    try:
        values = {k: float(v["fitted"]) for k, v in base.items()}
        values.update({f"{e}.{k}": float(v) for e, ps in params.items()
                       for k, v in ps.items()})
    except (TypeError, KeyError, ValueError, AttributeError):
        raise VtableError(f"{path}: 'base' or 'final_params' is not as "
                          "`vtable diagnose --json` writes them") from None
    return values


def diagnosis_reading(path: str, runs: list[Run]) -> str | None:
    """What a diagnosis found its runs' force channels measure (`force_reading`, a reading
    it kept), where `runs` do not declare it either; None otherwise."""
    r = _diagnosis_json(path).get("force_reading")
    if not isinstance(r, dict) or r.get("found") not in OTHER or r.get("found") == \
            r.get("assumed") or not undeclared(runs):
        return None
    return r["found"]


def calibrated(runs: list[Run], effects: list[str], calibration: Calibration,
               from_: str | None, measured_runs: list[Run]) -> tuple[TableModel, str]:
    """The model a drive is computed on and how it was had: the diagnosis's final model
    at its fitted values (`from_`, no fit), refitted from there when effects are added
    (`--with`) or lab runs join the campaign (`--update`); otherwise the base and the
    effects calibrated on the runs."""
    cal = calibration
    if from_:
        diag_effects = effects_from(from_)
        values = diagnosis_values(from_)
        try:
            reused = (None if values is None else
                      TableModel(diag_effects, calibration=cal).at(runs, values, source=from_))
        except VtableError as e:  # made on other runs: its values do not fit these
            reused, why = None, f"{e}"
        else:
            why = (f"{from_} holds no fitted values (base, final_params)"
                   if reused is None else "")
        if reused is not None:
            if (found := diagnosis_reading(from_, runs)) is not None:  # as it read them
                reused.physics_ = dataclasses.replace(reused.physics_, force_measured=found)
            extra = [e for e in effects if e not in diag_effects]
            if not extra and not measured_runs:
                return reused, f"the diagnosis's final model as fitted ({from_})"
            model = TableModel(extra, start=reused.physics_, calibration=cal,
                               choose=extra)  # the diagnosis's storeys kept
            return model.fit(runs + measured_runs), (
                f"the diagnosis's final model ({from_}) refitted"
                + (f" with {', '.join(extra)}" if extra else "")
                + (" on the lab run(s) too" if measured_runs else ""))
        effects = list(dict.fromkeys(effects + diag_effects))
        how = f"{why}: its final effects calibrated again on these runs"
    else:
        how = "calibrated on the runs"
    return TableModel(effects, calibration=cal).fit(runs + measured_runs), how


def drive(paths: Sequence[str], target: str, out: str, target_unit: str = "in",
          objective: str = "effective", with_: Sequence[str] = (), from_: str | None = None,
          calibrate: str = "", regularisation: float = REGULARISATION, cap: float = CAP,
          update: Sequence[str] = (), fmt: str = "csv", png: str | None = None,
          target_peak: float | None = None, band: float = BAND_HZ[1],
          report: str | None = None) -> DriveResult:
    """Calibrate the model of the runs (the base and the effects `with_`), or take a
    diagnosis's final model at its fitted values (`from_`; `calibrated`), compute the
    drive for `target` and write it to `out` (STEM.csv + STEM.toml: the drive as h_span
    with the model's predicted channels; STEM.txt, two columns, with `fmt` "txt").
    `update`: runs the lab measured with the previous drive; the model is recalibrated
    with them and the drive corrected from the last one's measured miss
    (`compensate(measured=...)`)."""
    runs = [align(r) for r in campaign(list(paths))]
    measured_runs = [align(r) for r in campaign(list(update))] if update else []
    tgt = read_target(target, target_unit, peak=target_peak)
    # before the model is calibrated: a bare table has no effective height to drive
    h = effective_height(runs[0], bare=None if objective == "effective" else 0.0)
    model, how = calibrated(runs, list(dict.fromkeys(with_)), Calibration.parse(calibrate),
                            from_, measured_runs)
    measured = None
    if measured_runs:
        measured = _measured(measured_runs[-1], tgt, h, objective)
    res = compensate(model, tgt, h, objective, regularisation, cap, measured=measured,
                     band_hz=band)
    res.notes.append(f"model: {how}; {len(runs)} run(s)"
                     + (f" and {len(measured_runs)} lab run(s) of a previous drive"
                        if measured_runs else "")
                     + (f", with {', '.join(model.physics_.effects)}"
                        if model.physics_.effects else ""))
    res.notes.append(f"lab runs used by this drive: {len(measured_runs)}")
    _write(res, runs[0], out, fmt)
    if png:
        res.plot(png)
    if report:
        res.files.append(res.write_report(report))
    return res


def _measured(run: Run, tgt: Target, h: float, objective: str
              ) -> tuple[np.ndarray, ...]:
    """(the drive played, the objective motion measured and, when the run has the
    accelerometers, its acceleration) of a lab run, at the target's rate and length."""
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
    pitch = objective == "effective" and run.has("pitch_disp")
    if pitch:
        y = y + h * np.interp(t, tr, run.channels["pitch_disp"])
    if not run.has("avg_hacc") or (pitch and not run.has("pitch_acc")):
        return d, y
    a = np.interp(t, tr, run.channels["avg_hacc"])
    if pitch:
        a = a + h * np.interp(t, tr, run.channels["pitch_acc"])
    return d, y, a


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
    # the target starts after REST_S of rest (room for the drive to lead it): a lab aligning
    # target and measurement must know it (docs/drive.md)
    meta["command"] = {"lead_s": REST_S}
    file_units = {k: template.units.get(k, FORMAT_UNITS.get(k, "1")) for k in ch}
    run = Run(Path(out).name, t, ch, file_units, meta)
    res.files += list(write_run(run, out))
    if fmt == "txt":
        rows = "\n".join(f"{a:.6f} {b:.8g}" for a, b in
                         zip(t, units.from_si(res.drive.drive, "in"), strict=True))
        res.files.append(write_text(Path(f"{out}.txt"),
                                    f"# time (s), drive (in) at {DRIVE_FS:g} Hz\n{rows}\n"))
