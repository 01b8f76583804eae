"""A diagnosis in Rerun: measured and model channels and residuals before and after each
added effect (bulk, columnar), and the error history on a 'round' timeline."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from vtable.diagnose.compare import GROUPS, group_prediction, group_signal


def log_diagnosis(d, diag, path: str | Path, application_id: str = "vtable-diagnosis") -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    rec = rr.RecordingStream(application_id)
    rec.save(str(path))
    stages = [("start", diag.start_fitted)]
    stages += [(f"{i}_{r.added}", r_ph) for i, (r, r_ph) in
               enumerate(((r, c.physics) for r in d.rounds for c in r.ranking[:1]
                          if r.added), 1)]
    for stage, ph in stages:
        pred = diag.predict(ph)
        for run in diag.runs:
            short = Path(run.name).name
            times = [rr.TimeColumn("time", duration=run.time - run.time[0])]
            for g in GROUPS:
                y = group_signal(run, g)
                yhat = group_prediction(pred[run.name], run, g)
                if y is None or yhat is None:
                    continue
                key = g.replace(" ", "_")
                if stage == "start":
                    rr.send_columns(f"runs/{short}/{key}/measured", indexes=times,
                                    columns=rr.Scalars.columns(scalars=y), recording=rec)
                rr.send_columns(f"runs/{short}/{key}/model_{stage}", indexes=times,
                                columns=rr.Scalars.columns(scalars=yhat), recording=rec)
                rr.send_columns(f"runs/{short}/{key}/residual_{stage}", indexes=times,
                                columns=rr.Scalars.columns(scalars=yhat - y), recording=rec)
    hist = d.history()
    idx = [rr.TimeColumn("round", sequence=np.arange(len(hist)))]
    rr.send_columns("diagnosis/error", indexes=idx, recording=rec,
                    columns=rr.Scalars.columns(scalars=[e for _, e in hist]))
    rr.send_columns("diagnosis/noise_floor", indexes=idx, recording=rec,
                    columns=rr.Scalars.columns(scalars=[d.noise_floor] * len(hist)))
    rec.log("diagnosis/verdict", rr.TextDocument(d.verdict), static=True)
    rec.send_blueprint(rrb.Blueprint(rrb.Horizontal(
        rrb.Vertical(*[rrb.TimeSeriesView(name=f"{Path(r.name).name}", origin=f"runs/"
                                          f"{Path(r.name).name}") for r in diag.runs]),
        rrb.Vertical(rrb.TimeSeriesView(name="error history", origin="diagnosis"),
                     rrb.TextDocumentView(origin="diagnosis/verdict")))))
    rec.flush()
    return path
