"""The diagnosis's verbs: how a model with given effects fits measured runs (`compare`),
and the search for the effects the model is missing (`diagnose`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from vtable.diagnose.calibration import Calibration
from vtable.diagnose.engine import Diagnoser
from vtable.diagnose.model import TableModel
from vtable.diagnose.reading import SAID, force_stage, undeclared
from vtable.diagnose.result import Diagnosis, DiagnosisInterrupted, ModelComparison
from vtable.errors import VtableError
from vtable.ident.drive import align
from vtable.runs import campaign

__all__ = ["DiagnosisInterrupted", "compare", "diagnose"]


def compare(paths: Sequence[str], effects: Sequence[str] = (), calibrate: str = "",
            rerun: str | None = None, report: str | None = None) -> ModelComparison:
    """How the model with `effects` fits the runs (fitted on the training segments,
    scored on the held-out ones; the base calibrated as `calibrate` says, see
    `vtable.diagnose.calibration.Calibration.parse`); writes the Rerun recording
    (`rerun`) and HTML report (`report`) asked for (`ModelComparison.plot`)."""
    cal = Calibration.parse(calibrate)  # a bad setting said before the runs are read
    runs = [align(r) for r in campaign(paths)]
    m = TableModel(effects, calibration=cal).fit(runs)
    c = ModelComparison.of(m)
    if undeclared(runs) and force_stage(m.physics_, m.vt):  # the two readings differ
        c.notes.append(f"the runs do not declare what their force channels measure "
                       f"([table.horizontal] force_measured): read as {SAID[m.vt.force_measured]}"
                       f" (the table's); declare it, or let `vtable diagnose` try the other")
    c.plot(report=report, rerun=rerun)
    return c


def diagnose(paths: Sequence[str], with_: Sequence[str] = (), catalog: Sequence[str] = (),
             max_rounds: int = 4, progress: Callable | None = None, rerun: str | None = None,
             report: str | None = None, calibrate: str = "",
             scheduler: str | None = None) -> Diagnosis:
    """The diagnosis loop on the runs; writes the Rerun recording (`rerun`) and the HTML
    report (`report`) asked for (`Diagnosis.plot`, listed in its `files`); the candidates
    are fitted on a local Dask cluster, or on the one whose scheduler is at `scheduler`.
    Ctrl-C raises `DiagnosisInterrupted` carrying the rounds finished (`partial`,
    `interrupted` true)."""
    if max_rounds < 1:
        raise VtableError(f"--max-rounds must be at least 1, got {max_rounds}")
    d = Diagnoser([align(r) for r in campaign(paths)], list(with_), catalog=list(catalog) or None,
                  progress=progress, max_rounds=max_rounds,
                  calibration=Calibration.parse(calibrate), scheduler=scheduler).diagnose()
    d.plot(report=report, rerun=rerun)
    return d
