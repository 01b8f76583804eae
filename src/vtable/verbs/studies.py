"""The interaction studies' verbs: the five models of §9.4 for one specimen and record
(`assess`), and a heights x records study on Dask (`study`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from vtable.params.specimen import SDOFSpecimen
from vtable.results import AssessmentResult, StudyResult
from vtable.signals.processing import process_record
from vtable.signals.records import load_record
from vtable.sim.experiment import load_specimen
from vtable.studies import interaction as ia
from vtable.studies import yielding
from vtable.studies.scaleout import height_record_study, run_study
from vtable.viz import figures


def assess(specimen: str = "sdof_frame", record: str = "elcentro", raw: bool = False,
           out: str = "vtable-assess") -> AssessmentResult:
    """The five models of §9.4 for a specimen and a record: coupled modes, PSV spectra,
    the verdict, and the sweeps of Figs 9.4-9.12 (written as PNGs)."""
    rec = load_record(record)
    if raw:
        acc, dt, label = rec.acc, rec.dt, rec.name
    else:
        cmd = process_record(rec)
        acc, dt, label = cmd.acceleration, cmd.dt, f"{rec.name} (§9.2 processed)"
    spec = load_specimen(specimen)
    res = ia.assess(spec, acc, dt, label)
    s = res.specimen
    folder = Path(out)
    f_s = np.linspace(0.5, 10.0, 39)
    ref = np.column_stack([f_s, np.full_like(f_s, s.damping)])
    xi = np.linspace(0.0, 0.20, 21)
    files = [
        figures.psv_spectra_png(folder / "psv_spectra.png", res.periods, res.psv,
                                f"{s.title}: PSV, {label}, ξ_s {100 * s.damping:.0f} %"),
        figures.coupled_sweep_png(folder / "coupled_vs_frequency.png", f_s, "f_s (Hz)",
                                  ia.sweep(s, "frequency", f_s), ref,
                                  "coupled mode vs structural frequency (Figs 9.4-9.5)"),
        figures.coupled_sweep_png(folder / "coupled_vs_damping.png", 100 * xi, "ξ_s (%)",
                                  ia.sweep(s, "damping", xi, names=["hybrid"]),
                                  np.column_stack([np.full_like(xi, s.frequency), xi]),
                                  "coupled mode vs structural damping (Figs 9.7-9.8)"),
    ]
    for par, label_x in (("weight", "mass"), ("height", "height")):
        curves = {f"{label_x} x{k:g}": ia.sweep(replace(s, **{par: getattr(s, par) * k}),
                                                "frequency", f_s, names=["hybrid"])["hybrid"]
                  for k in (0.5, 1.0, 1.5)}
        files.append(figures.coupled_sweep_png(
            folder / f"coupled_vs_{label_x}.png", f_s, "f_s (Hz)", curves, ref,
            f"hybrid model: varying structural {label_x} (Figs 9.9-9.12)"))
    notes = list(getattr(rec, "notes", ()))
    ductility = None
    if getattr(spec, "hysteresis", None) is not None:
        if not isinstance(spec, SDOFSpecimen):
            notes.append("the ductility sweep takes a sdof specimen; this building's yielding "
                         "storeys are assessed through its first mode's linear models only")
        else:
            cmd = process_record(rec)  # the table's displacement command (also with --raw)
            if raw:
                notes.append("the ductility sweep plays the §9.2-processed record (the table "
                             "model needs its displacement command)")
            periods = np.unique(np.append(np.geomspace(0.1, 2.0, 12), 1.0 / s.frequency))
            ductility = yielding.sweep(spec, cmd.time, cmd.displacement, cmd.acceleration,
                                       periods)
            files.append(figures.ductility_png(
                folder / "ductility_vs_period.png", ductility, 1.0 / s.frequency,
                f"{s.title}: ductility and residual drift, {rec.name}"))
    return AssessmentResult(res.verdict(), s.title, label,
                      {k: {"f_hz": f, "damping": z} for k, (f, z) in res.modes.items()},
                      res.psv_at_specimen, res.rocking_share, res.elongation,
                      res.compensated_error, [Path(f) for f in files], notes, ductility)


def study(store: str, heights: Sequence[float], records: Sequence[str] = ("elcentro",),
          specimen: str = "sdof_frame", model: str = "virtual", duration: float | None = None,
          scheduler: str | None = None, workers: int = 2) -> StudyResult:
    """A heights x records study on Dask, stored as it runs and resumable."""
    common: dict[str, Any] = {"specimen": specimen}
    if duration is not None or model == "virtual":
        common["duration"] = duration if duration is not None else 4.0
    s = height_record_study(list(heights), list(records), model, **common)
    return StudyResult(store, model, run_study(s, store, scheduler=scheduler, n_workers=workers))
