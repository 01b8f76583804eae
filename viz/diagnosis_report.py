"""The HTML report of a diagnosis: verdict, what remains unexplained, the notes, the base
calibration, ranking tables with evidence and fit flags, the error waterfall, Bode plots
of every run (dB on a log frequency axis with the measured ±1σ band, unwrapped phase,
coherence beneath, the start and final models overlaid), held-out time histories with
the final model's fit % per channel group and the residual, and, for runs with storey
channels, each storey's shear against its drift (matplotlib, embedded PNGs).
Every axis names its unit; transfer functions are shown in the run format's units per inch
of command. It renders the stages
the diagnosis kept (models, predictions, comparisons) and simulates nothing; `d` is a
`vtable.diagnose.result.Diagnosis`, which draws itself through this module (`plot`)."""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from vtable import display
from vtable.diagnose.groups import GROUP_UNITS, group_prediction, group_signal, short
from vtable.diagnose.sampling import segments
from vtable.errors import VtableError
from vtable.fileio import write_text
from vtable.ident.frames import SHORTEST, frame_for_averages, frame_for_mode
from vtable.ident.structure import lowest_declared_mode
from vtable.ident.tf import transfer_function
from vtable.viz.figures import bode_figure, magnitude_band  # noqa: F401 (re-exported)

plt.switch_backend("Agg")  # figures are embedded as PNG: no window, whatever the default

PRETTY = {"rad/s2": "rad/s²"}


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode()


def waterfall(d: Any):
    hist = d.history()
    fig, ax = plt.subplots(figsize=(6.5, 3.2))
    labels = [h[0] for h in hist]
    vals = [100 * h[1] for h in hist]
    prev = vals[0]
    ax.bar(0, vals[0], color="0.5")
    for i, v in enumerate(vals[1:], 1):
        ax.bar(i, v - prev, bottom=prev, color="tab:green")
        prev = v
    ax.bar(len(vals), vals[-1], color="tab:blue")
    ax.axhline(100 * d.noise_floor, color="tab:red", ls="--", label="noise floor")
    ax.set_xticks(range(len(vals) + 1), [*labels, "final"], rotation=20, ha="right")
    ax.set_ylabel("held-out error (NRMS, %)")
    ax.set_xlabel("model: fitted start, each added effect, final")
    ax.set_title("error waterfall")
    ax.legend()
    fig.tight_layout()
    return fig


#: the frames of the report's transfer functions: the finest resolution at or above
#: `BODE_RESOLUTION_HZ` that still averages `BODE_AVERAGES` half-overlapping frames
BODE_RESOLUTION_HZ = 0.05
BODE_AVERAGES = 8
#: the start and final models' colours (the measured trace is black, drawn on top)
MODEL_COLORS = {"start model": "tab:orange", "final model": "tab:blue", "model": "tab:blue"}


def model_stages(d: Any) -> list[tuple[str, Any]]:
    """The stages drawn: the start and final models of a diagnosis, or the one model of a
    comparison (`vtable compare --report`)."""
    if len(d.stages) > 1:
        return [("start model", d.stages[0]), ("final model", d.stages[-1])]
    return [("model", s) for s in d.stages]


def bode_frames(n: int, fs: float, mode: tuple[float, float] | None = None) -> int:
    """Samples per frame: with the declared specimen's lowest mode (f, ξ), the frames
    that resolve it (`vtable.ident.frames.frame_for_mode`: its peak and notch shown, the
    averages warned in the axis label); else the longest power of two with at least
    `BODE_AVERAGES` half-overlapping frames in `n` samples, at most fs /
    `BODE_RESOLUTION_HZ` (`frame_for_averages`; its shortest frame when none gives them)."""
    if mode is not None:
        try:
            return frame_for_mode(n, fs, *mode).nperseg
        except VtableError:  # too short to hold a fit of the mode: the averages' rule
            pass
    longest = 1 << int(np.log2(fs / BODE_RESOLUTION_HZ))
    return frame_for_averages(n, BODE_AVERAGES, longest) or SHORTEST


def tf_overlay(d: Any, group: str, run=None):
    """A Bode plot of `group` over the command h_span for `run` (default: the longest):
    magnitude in dB on a log frequency axis with the measured ±1σ band, unwrapped phase,
    coherence beneath; the start and final models overlaid, the measured trace on top."""
    run = run if run is not None else max(d.runs, key=lambda r: len(r.time))
    x = run.channel("h_span")
    y = group_signal(run, group)
    if y is None:
        return None
    n = bode_frames(len(x), run.fs, lowest_declared_mode(run))
    unit, per = (display.unit_for(u, display.run_family(run), run.units.values())
                 for u in (GROUP_UNITS[group], "in"))  # the run's own units
    scale = display.from_si(1.0, unit) / display.from_si(1.0, per)  # SI ratio -> unit/per
    tm = transfer_function(x, y, run.fs, n)
    sel = (tm.f >= 2 * tm.resolution_hz) & (tm.f <= min(30.0, 0.4 * run.fs))
    models = []
    for label, stage in model_stages(d):
        yhat = group_prediction(stage.predictions[run.name], run, group)
        if yhat is not None and np.any(yhat):  # a model without this motion: not drawn
            tp = transfer_function(x, yhat, run.fs, n)
            models.append((label, scale * tp.H[sel], MODEL_COLORS[label]))
    return bode_figure(
        tm.f[sel], scale * tm.H[sel], tm.coherence[sel], tm.averages, models,
        magnitude_label=f"magnitude (dB re 1 {PRETTY.get(unit, unit)}/{per})",
        title=f"{group} / command h_span, {short(run.name)}",
        xlabel=f"frequency (Hz); {tm.averages} averages of {n}-point frames, "
               f"Δf {tm.resolution_hz:.3g} Hz")


def fit_percent(y: np.ndarray, yhat: np.ndarray) -> float:
    """MATLAB `compare`'s fit: 100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖), in %."""
    den = float(np.linalg.norm(y - np.mean(y)))
    return float("nan") if den == 0 else 100.0 * (1.0 - np.linalg.norm(y - yhat) / den)


def time_histories(d: Any, run, groups=("table displacement", "table acceleration",
                                        "structure acceleration")):
    """Measured against the final model on the held-out segment of `run`, one panel per
    channel group with its fit % in the legend, and the residual beneath each."""
    held = segments(run)[1]
    final = model_stages(d)[-1][0] if d.stages else "final model"
    rows = []
    for g in groups:
        y = group_signal(run, g)
        yhat = group_prediction(d.stages[-1].predictions[run.name], run, g) if d.stages \
            else None
        if y is not None and yhat is not None:
            rows.append((g, y[held], yhat[held]))
    if not rows:
        return None
    t = run.time[held] - run.time[0]
    fig, ax = plt.subplots(2 * len(rows), 1, sharex=True, figsize=(7, 2.0 * len(rows) + 1.6),
                           gridspec_kw={"height_ratios": [2, 1] * len(rows)})
    for k, (g, y, yhat) in enumerate(rows):
        unit = display.unit_for(GROUP_UNITS[g], display.run_family(run), run.units.values())
        shown = PRETTY.get(unit, unit)
        ym, yh = display.from_si(y, unit), display.from_si(yhat, unit)
        a, r = ax[2 * k], ax[2 * k + 1]
        a.plot(t, ym, "k-", lw=1.0, label="measured")
        a.plot(t, yh, color=MODEL_COLORS[final], lw=0.9,
               label=f"{final}: fit {fit_percent(y, yhat):.1f} %")
        a.set_ylabel(f"{g}\n({shown})", fontsize=8)
        a.legend(fontsize=7, loc="upper right")
        r.plot(t, yh - ym, color="tab:red", lw=0.8)
        r.set_ylabel(f"residual\n({shown})", fontsize=8)
        for x in (a, r):
            x.grid(alpha=0.3)
    ax[-1].set_xlabel(f"time from the run's start (s); held-out segment of {short(run.name)}")
    fig.tight_layout()
    return fig


def hysteresis_loops(d: Any, run):
    """Each storey's shear against its drift over the whole of `run` (the run's
    floorK_drift and floorK_shear), measured and the final model's: a yielding storey's
    loops, an elastic one's line. None when the run has no storey channels."""
    storeys = [k for k in range(1, 51) if run.has(f"floor{k}_drift")
               and run.has(f"floor{k}_shear")]
    if not storeys or not d.stages:
        return None
    pred = d.stages[-1].predictions[run.name]
    final = model_stages(d)[-1][0]
    fam = display.run_family(run)
    du = display.unit_for("in", fam, run.units.values())
    fu = display.unit_for("kip", fam, run.units.values())
    fig, ax = plt.subplots(1, len(storeys), figsize=(3.4 * len(storeys) + 0.6, 3.4),
                           squeeze=False)
    for a, k in zip(ax[0], storeys, strict=True):
        u, v = run.channels[f"floor{k}_drift"], run.channels[f"floor{k}_shear"]
        a.plot(display.from_si(u, du), display.from_si(v, fu), "k-", lw=0.6, label="measured")
        if f"floor{k}_drift" in pred and f"floor{k}_shear" in pred:
            a.plot(display.from_si(pred[f"floor{k}_drift"], du),
                   display.from_si(pred[f"floor{k}_shear"], fu), color=MODEL_COLORS[final],
                   lw=0.8, label=final)
        a.set_xlabel(f"storey {k} drift ({du})")
        a.set_ylabel(f"storey {k} shear ({fu})")
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
    fig.suptitle(f"{short(run.name)}: storey shear against drift", fontsize=9)
    fig.tight_layout()
    return fig


def _plus(effects) -> str:
    return (" + " + ", ".join(effects)) if effects else ""


def write_report(d: Any, path: str | Path) -> Path:
    """Write the HTML report of `d` to `path`."""
    e = html.escape
    start = "—" if d.start_error is None else f"{d.start_error:.2%}"
    final = "—" if d.final_error is None else f"{d.final_error:.2%}"
    u = d.unexplained
    title = html.escape(d.title)
    parts = [f"<html><head><meta charset='utf-8'><title>{title}</title>"
             "<style>body{font-family:sans-serif;max-width:60em;margin:auto}"
             "td,th{padding:2px 8px;border-bottom:1px solid #ddd}</style></head><body>",
             f"<h1>{title}</h1>",
             *([f"<p style='font-size:1.2em'><b>{e(d.headline)}</b></p>"] if d.headline else []),
             *(["<ul>" + "".join(f"<li>{e(f['what'])}"
                                 + (f" <i>({e(', '.join(f['runs']))})</i>" if f['runs'] else "")
                                 + f"<br>→ {e(f['action'])}</li>" for f in d.findings)
                + "</ul>"] if d.findings else []),
             f"<details><summary>Verdict (the statistics)</summary><p>{e(d.verdict)}</p>"
             "</details>",
             "<p><b>Unexplained:</b> " + (e("none: the final error is consistent with the "
                                             "noise floor") if u is None else
                                           e(f"the final error is {u['ratio_to_floor']:.1f} x "
                                             f"the noise floor; {u['where']}")) + "</p>",
             f"<p>Runs: {e(', '.join(r.name for r in d.runs))}. Starting model: "
             f"linear servo loop + specimen{_plus(d.start_effects)}."
             f" Held-out error {start} → {final}; noise floor {d.noise_floor:.2%}.</p>"]
    if d.notes:
        parts.append("<h2>Notes</h2><ul>" + "".join(f"<li>{e(n)}</li>" for n in d.notes)
                     + "</ul>")
    if d.base:
        parts.append("<h2>Base parameters (calibrated)</h2><table><tr><th>parameter</th>"
                     "<th>declared</th><th>fitted</th><th>bounds</th><th>unit</th></tr>")
        for k, v in d.base.items():
            parts.append(f"<tr><td>{e(k)}</td><td>{v['declared']:.4g}</td>"
                         f"<td>{v['fitted']:.4g}</td><td>{v['bounds'][0]:g} – "
                         f"{v['bounds'][1]:g}</td><td>{e(v.get('unit', ''))}</td></tr>")
        parts.append("</table>")
    if d.history():
        parts += ["<h2 id='waterfall'>Error waterfall</h2>",
                  f"<img src='data:image/png;base64,{_png(waterfall(d))}'>"]
    for i, r in enumerate(d.rounds, 1):
        parts.append(f"<h2>Round {i}: {'added ' + e(r.added) if r.added else 'nothing added'}"
                     "</h2><table><tr><th>rank</th><th>effect</th><th>held-out error</th>"
                     "<th>evidence</th><th>fit at a bound</th></tr>")
        for k, c in enumerate(r.ranking, 1):
            parts.append(f"<tr><td>{k}</td><td>{e(c.effect)}</td><td>{c.error_after:.2%}</td>"
                         f"<td>{e(c.evidence)}</td><td>{e('; '.join(c.flags))}</td></tr>")
        parts.append("</table>")
    if d.stages and d.comparison_start is not None and d.comparison_final is not None:
        parts.append("<h2 id='tf'>Transfer functions: measured, start and final models</h2>")
        for run in d.runs:
            for g in ("table displacement", "pitch", "structure acceleration"):
                fig = tf_overlay(d, g, run)
                if fig is not None:
                    parts.append(f"<img src='data:image/png;base64,{_png(fig)}'>")
        parts.append("<h2 id='time'>Time histories: measured and final model (held out)</h2>")
        for run in d.runs:
            fig = time_histories(d, run)
            if fig is not None:
                parts.append(f"<img src='data:image/png;base64,{_png(fig)}'>")
        loops = [fig for fig in (hysteresis_loops(d, run) for run in d.runs) if fig is not None]
        if loops:
            parts.append("<h2 id='loops'>Hysteresis loops: storey shear against drift "
                         "(measured and final model)</h2>")
            parts += [f"<img src='data:image/png;base64,{_png(fig)}'>" for fig in loops]
        parts.append("<h2>Error per channel group (held out, NRMS)</h2><table><tr><th>run</th>"
                     "<th>group</th><th>start</th><th>final</th></tr>")
        for run, errs in d.comparison_start.per_run.items():
            for g, v in errs.items():
                f = d.comparison_final.per_run[run].get(g, float("nan"))
                parts.append(f"<tr><td>{e(short(run))}</td><td>{e(g)}</td>"
                             f"<td>{v:.2%}</td><td>{f:.2%}</td></tr>")
        parts.append("</table>")
    parts.append("</body></html>")
    return write_text(path, "\n".join(parts))

