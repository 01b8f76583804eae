"""A diagnosis in Rerun: measured and model channels and residuals before and after each
added effect (bulk, columnar), in the run format's units, and the error history.

Layout (blueprint): one tab per run, and in it two tabs of 2-column grids with one
TimeSeriesView per channel group, named with its unit ("table displacement (in)",
"structure acceleration (g)", ...): "measured & models" shows the measured signal (black,
wider) and the model of every stage (a colour each, Okabe-Ito); "residuals" shows each
stage's model − measured (the stage's hue, lighter). The series have short names
("measured", "0: start", "1: pitch_flexibility"; the unit is in the view's name), and a
legend only where it tells something the view does not (`legend`): a diagnosis's models
list theirs in the top right corner, the y range leaving room above the data for it, so
it covers no data; a comparison's one model (black measured, blue model: the tab's name
says so) and the residuals (each in its model's hue, lighter) have none. Beside them, the
error history and a text with the verdict, the colours, what remains unexplained and the
notes. Entities: runs/<run>/<group>/measured, .../model/<k_stage>, .../residual/<k_stage>
(0_start, 1_<effect>, ...).

Timelines: the channels are on "time" (s from the run's start, at the analysis rate), the
error history on "round" (0 = the fitted starting model, k = after the k-th added effect).
A Rerun 0.41 view plots the timeline selected in the time panel (a view cannot choose its
own), so the view of the history is a static bar chart, which every timeline shows (its
name lists each round's error); the time panel starts on "time". The side panels open
collapsed so the plots have the width.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from rerun.chunk import RrdReader

from vtable import display, units
from vtable.diagnose.groups import (
    GROUP_UNITS,
    group_prediction,
    group_signal,
    run_groups,
    short,
)
from vtable.viz.recording import rrd_file

#: legends in the top right corner: the first seconds, where a run starts, stay visible
LEGEND = rrb.PlotLegend(corner=rrb.Corner2D.RightTop, visible=True)
#: no legend: a view whose series the view's (or tab's) name already tells apart
NO_LEGEND = rrb.PlotLegend(corner=rrb.Corner2D.RightTop, visible=False)
#: how a unit is written in view and series names
PRETTY = {"rad/s2": "rad/s²", "in/s2": "in/s²", "m/s2": "m/s²"}
#: the measured trace in black; each model stage in its own colour (Okabe-Ito, readable by
#: colour-blind eyes), its residual in the same hue, lighter
MEASURED = [20, 20, 20]
STAGE_COLORS = ([0, 114, 178], [230, 159, 0], [0, 158, 115], [204, 121, 167],
                [213, 94, 0], [86, 180, 233], [240, 228, 66])
_COLOR_NAMES = ("blue", "orange", "green", "reddish purple", "vermilion", "sky blue", "yellow")


def stage_color(k: int, residual: bool = False) -> list[int]:
    """Stage k's colour (its residual's: halfway to white)."""
    c = STAGE_COLORS[k % len(STAGE_COLORS)]
    return [round(v + (255 - v) * 0.5) for v in c] if residual else list(c)


def headroom(lo: float, span: float, n_entries: int) -> tuple[float, float]:
    """The y range of a view whose data spans [lo, lo + span]: room above the data for a
    legend of `n_entries` lines in the top corner (each line ~ 9 % of a view's height,
    the views of a 2-column grid), so that the legend covers no data."""
    top = min(0.12 + 0.09 * n_entries, 0.6)  # the fraction of the height the legend takes
    return lo - 0.05 * span, lo + span + span * (top + 0.05) / (1 - top)


def stage_key(k: int, stage: str) -> str:
    """A stage's entity name, numbered so that views and legends list the stages in their
    order: "0_start", "1_pitch_flexibility", ... (a comparison's one model: "model")."""
    return stage if stage == "model" or stage[:1].isdigit() else f"{k}_{stage}"


def group_key(group: str) -> str:
    return group.replace(" ", "_")


def series_name(k: int, stage: str) -> str:
    """A stage's series name, short so that a legend stays narrow: "model" (a
    comparison's one model), else "0: start", "1: pitch_flexibility", ..."""
    key = stage_key(k, stage)
    return key if key == "model" else key.replace("_", ": ", 1)


def legend(n_series: int) -> rrb.PlotLegend:
    """`LEGEND` for a view of more than two series, else `NO_LEGEND` (measured and one
    model, black and blue, or one residual: the names of the view and its tab say which)."""
    return LEGEND if n_series > 2 else NO_LEGEND


def _series(rec: rr.RecordingStream, path: str, times, values: np.ndarray, label: str,
            color: list[int], width: float = 1.0) -> None:
    rr.send_columns(path, indexes=times, columns=rr.Scalars.columns(scalars=values),
                    recording=rec)
    rec.log(path, rr.SeriesLines(names=label, colors=[color], widths=[width]), static=True)


def _text(d) -> str:
    lines = [f"**{d.headline}**", ""] if d.headline else []
    for f in d.findings:
        lines.append(f"- {f['what']}" + (f" ({', '.join(f['runs'])})" if f["runs"] else "")
                     + f" → {f['action']}")
    lines += ["", f"**Verdict:** {d.verdict}", ""]
    u = d.unexplained
    lines.append("**Unexplained:** " + ("none (the final error is consistent with the noise "
                                        "floor)" if u is None else
                                        f"{u['ratio_to_floor']:.1f} x the noise floor; "
                                        f"{u['where']}"))
    lines += ["", "Measured = each run at the analysis rate (see the notes).", "",
              "**Colours:** measured in black (wider); " + "; ".join(
                  f"{series_name(k, s.label)} in {_COLOR_NAMES[k % len(_COLOR_NAMES)]}"
                  for k, s in enumerate(d.stages)) + "; each residual in its model's "
              "colour, lighter.", ""]
    if d.notes:
        lines += ["**Notes:**", *[f"- {n}" for n in d.notes]]
    return "\n".join(lines)


def _loops(rec: rr.RecordingStream, run, pred: dict[str, np.ndarray], base: str,
           color: list[int]) -> list:
    """Each storey's shear against its drift, measured (black) and as the final model
    predicts it, both scaled by the measured peaks (a 2D view draws x and y at one scale;
    the shear negated for Rerun's downward y); their views."""
    views = []
    k = 1
    while run.has(f"floor{k}_drift") and run.has(f"floor{k}_shear"):
        d = units.from_si(run.channels[f"floor{k}_drift"], "in")
        v = units.from_si(run.channels[f"floor{k}_shear"], "kip")
        dm, vm = float(np.max(np.abs(d))) or 1.0, float(np.max(np.abs(v))) or 1.0
        ent = f"{base}/storey{k}"
        rec.log(f"{ent}/measured", rr.LineStrips2D([np.column_stack([d / dm, -v / vm])],
                                                   colors=[MEASURED], radii=[0.004]),
                static=True)
        if f"floor{k}_drift" in pred and f"floor{k}_shear" in pred:
            dp = units.from_si(pred[f"floor{k}_drift"], "in")
            vp = units.from_si(pred[f"floor{k}_shear"], "kip")
            rec.log(f"{ent}/model", rr.LineStrips2D([np.column_stack([dp / dm, -vp / vm])],
                                                    colors=[color], radii=[0.004]),
                    static=True)
        views.append(rrb.Spatial2DView(
            name=f"storey {k}: shear (up, ±{vm:.3g} kip) against drift (right, ±{dm:.3g} "
                 "in): measured black, the final model in its colour", origin=ent))
        k += 1
    return views


def log_diagnosis(d, path: str | Path, application_id: str = "vtable-diagnosis") -> Path:
    """Write the .rrd of diagnosis `d` (from the stages it kept: nothing is simulated again)
    to `path`."""
    path = Path(path)
    tabs = []
    with rrd_file(path, application_id) as rec:
        preds = [(st.label, st.predictions) for st in d.stages]
        for run in d.runs:
            name = short(run.name)
            times = [rr.TimeColumn("time", duration=run.time - run.time[0])]
            signals, residuals = [], []
            for g in run_groups(run):
                y = group_signal(run, g)
                if y is None:
                    continue
                unit = display.unit_for(GROUP_UNITS[g], display.run_family(run),
                                        run.units.values())  # the run's own units
                shown = PRETTY.get(unit, unit)
                base = f"runs/{name}/{group_key(g)}"
                ym = units.from_si(y, unit)
                _series(rec, f"{base}/measured", times, ym, "measured", MEASURED, 2.0)
                lo, hi = float(np.min(ym)), float(np.max(ym))
                n_models = 0
                for k, (stage, pred) in enumerate(preds):
                    yhat = group_prediction(pred[run.name], run, g)
                    if yhat is None:
                        continue
                    key, label = stage_key(k, stage), series_name(k, stage)
                    yh = units.from_si(yhat, unit)
                    lo, hi = min(lo, float(np.min(yh))), max(hi, float(np.max(yh)))
                    _series(rec, f"{base}/model/{key}", times, yh, label, stage_color(k))
                    _series(rec, f"{base}/residual/{key}", times, yh - ym, label,
                            stage_color(k, residual=True))
                    n_models += 1
                span = (hi - lo) or 1.0
                shown_legend = legend(1 + n_models)
                room = ({"axis_y": rrb.ScalarAxis(range=headroom(lo, span, 1 + n_models))}
                        if shown_legend is LEGEND else {})
                signals.append(rrb.TimeSeriesView(
                    name=f"{g} ({shown})", origin=base,
                    contents=["$origin/measured", "$origin/model/**"],
                    plot_legend=shown_legend, **room))
                residuals.append(rrb.TimeSeriesView(
                    name=f"{g}: model − measured ({shown})", origin=f"{base}/residual",
                    plot_legend=NO_LEGEND))
            loops = _loops(rec, run, d.stages[-1].predictions.get(run.name, {}) if d.stages
                           else {}, f"runs/{name}/loops", stage_color(len(preds) - 1))
            if signals:
                tabs.append(rrb.Tabs(rrb.Grid(*signals, grid_columns=2, name=(
                    "measured (black) & model (blue)" if len(preds) == 1 else
                    "measured & models")),
                                     rrb.Grid(*residuals, grid_columns=2, name="residuals"),
                                     *([rrb.Grid(*loops, grid_columns=2, name="storey loops")]
                                       if loops else []),
                                     name=name))
        hist = d.history()
        if hist:
            idx = [rr.TimeColumn("round", sequence=np.arange(len(hist)))]
            rr.send_columns("diagnosis/error", indexes=idx, recording=rec,
                            columns=rr.Scalars.columns(scalars=[e for _, e in hist]))
            rec.log("diagnosis/error", rr.SeriesLines(names="held-out error (NRMS, 1 = 100 %)",
                                                      colors=[stage_color(0)], widths=[2.0]),
                    static=True)
            rr.send_columns("diagnosis/noise_floor", indexes=idx, recording=rec,
                            columns=rr.Scalars.columns(scalars=[d.noise_floor] * len(hist)))
            rec.log("diagnosis/noise_floor", rr.SeriesLines(names="noise floor (NRMS)",
                                                            colors=[MEASURED]), static=True)
            rec.log("history", rr.BarChart([100 * e for _, e in hist],
                                           abscissa=np.arange(len(hist)),
                                           color=stage_color(len(hist) - 1)), static=True)
        rec.log("diagnosis/verdict", rr.TextDocument(_text(d), media_type="text/markdown"),
                static=True)
        rounds = " | ".join(f"{k}: {lab} {100 * e:.2f} %" for k, (lab, e) in enumerate(hist))
        side = rrb.Vertical(
            rrb.BarChartView(name=f"held-out error (%) by round (noise floor "
                                  f"{100 * d.noise_floor:.2f} %): {rounds}", origin="history",
                             plot_legend=rrb.PlotLegend(visible=False)),
            rrb.TextDocumentView(name="verdict and notes", origin="diagnosis/verdict"),
            row_shares=[2, 3])
        main = rrb.Tabs(*tabs) if tabs else rrb.TextDocumentView(origin="diagnosis/verdict")
        rec.send_blueprint(rrb.Blueprint(rrb.Horizontal(main, side, column_shares=[3, 2]),
                                         rrb.TimePanel(timeline="time", state="collapsed"),
                                         collapse_panels=True))
    return path


def read_blueprint_views(path: str | Path) -> list[dict[str, Any]]:
    """The views of an .rrd's blueprint: class ("TimeSeries", "BarChart", ...), name,
    origin ("/runs/run0/pitch"), the timelines of its visible time ranges and its legend
    ({"visible": bool, "corner": "RightTop", ...}, when set) (for tests and checks)."""

    reader = RrdReader(str(path))
    views: dict[str, dict[str, Any]] = {}
    for bp in reader.blueprints():
        for ch in reader.stream(store=bp).to_chunks():
            ent = str(ch.entity_path).lstrip("/")
            if not ent.startswith("view/"):
                continue
            key = "/".join(ent.split("/")[:2])
            rb = ch.to_record_batch()
            v = views.setdefault(key, {})
            for col in rb.schema.names:
                val = rb.column(col).to_pylist()[-1]
                one = val[0] if isinstance(val, list) and len(val) == 1 else val
                if col == "ViewBlueprint:class_identifier":
                    v["class"] = one
                elif col == "ViewBlueprint:display_name":
                    v["name"] = one
                elif col == "ViewBlueprint:space_origin":
                    v["origin"] = "/" + str(one).lstrip("/")
                elif col == "VisibleTimeRanges:ranges":
                    v["time_ranges"] = [r["timeline"] for r in val]
                elif col == "PlotLegend:visible":
                    v.setdefault("legend", {})["visible"] = bool(one)
                elif col == "PlotLegend:corner":
                    v.setdefault("legend", {})["corner"] = rrb.Corner2D(one).name
    return list(views.values())
