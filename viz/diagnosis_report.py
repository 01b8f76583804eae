"""The HTML report of a diagnosis: verdict, what remains unexplained, the notes, the base
calibration, ranking tables with evidence and fit flags, the error waterfall, Bode plots
of every run (dB on a log frequency axis with the measured ±1σ band where the coherence
supports it, unwrapped phase, coherence beneath, the start and final models overlaid),
held-out time histories with the final model's fit % per channel group and the residual,
and, for runs with storey channels, each storey's shear against its drift (matplotlib,
embedded PNGs at the page's width). The measured trace is drawn thin and black on top of
the models' wide, translucent lines, so both show where they agree.
Every axis names its unit; transfer functions are shown in the run format's units per inch
of command. It renders the stages
the diagnosis kept (models, predictions, comparisons) and simulates nothing; `d` is a
`vtable.diagnose.result.Diagnosis`, which draws itself through this module (`plot`). A
comparison (`vtable compare --report`, `Diagnosis.compared`) is drawn the same way with
its one model, and its headings and captions say so."""

from __future__ import annotations

import base64
import contextlib
import html
import io
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import scipy.signal

from vtable import display
from vtable.diagnose.groups import GROUP_UNITS, group_prediction, group_signal, short
from vtable.diagnose.prose import linear_model
from vtable.diagnose.sampling import segments
from vtable.diagnose.workers import running
from vtable.errors import VtableError, interrupted
from vtable.fileio import write_text
from vtable.ident.frames import SHORTEST, frame_for_averages, frame_for_mode
from vtable.ident.structure import lowest_declared_mode
from vtable.ident.tf import transfer_function
from vtable.viz.figures import (  # noqa: F401 (magnitude_band: re-exported)
    COHERENCE_MIN,
    COMMAND_POWER_MIN,
    LABEL_FONTSIZE,
    LEGEND_FONTSIZE,
    MEASURED_LW,
    MEASURED_Z,
    MODEL_ALPHA,
    MODEL_LW,
    MODEL_Z,
    WIDTH_IN,
    bode_figure,
    magnitude_band,
    style_axes,
)

plt.switch_backend("Agg")  # figures are embedded as PNG: no window, whatever the default

PRETTY = {"rad/s2": "rad/s²"}
#: the figures' resolution: `WIDTH_IN` x DPI = 1200 px, shown at the page's width
DPI = 120
#: the page: up to 1200 px of text and figures, each figure as wide as the page (scaled
#: down with a narrower window)
STYLE = ("body{font-family:sans-serif;max-width:75em;margin:auto;padding:0 1em}"
         "td,th{padding:2px 8px;border-bottom:1px solid #ddd}"
         "img{display:block;width:100%;max-width:100%;height:auto;margin:0.5em 0}")


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode()


def _img(fig) -> str:
    """`fig` as an <img> of the page's width (`STYLE`), its PNG embedded."""
    return _tag(_png(fig))


def _tag(png: str) -> str:
    return f"<img src='data:image/png;base64,{png}'>"


def _drawn(figure, d: Any, *args) -> str | None:
    """`figure(d, *args)`'s PNG (base64), or None where it draws nothing; a run given by
    its index in `d.runs`."""
    fig = figure(d, *(d.runs[a] if isinstance(a, _Run) else a for a in args))
    return None if fig is None else _png(fig)


class _Run(int):
    """A run of `d.runs` by its index (what a figure job sends instead of the run)."""


def _drawn_all(d: Any, jobs: list[tuple]) -> list[str | None]:
    """The PNGs of `jobs` ((figure, *args), `_drawn`), in order: on the workers of the
    local Dask cluster the diagnosis ran on, when it is still up (a figure is ~0.2 s of
    matplotlib; `vtable diagnose --report` draws a dozen), else here one by one — also
    when the workers cannot draw them (an effect registered in code, which they cannot
    load; workers gone)."""
    client = running()
    if client is not None and len(jobs) > 1:
        futures: list = []
        try:
            futures.append(client.scatter(d, hash=False, broadcast=True, timeout=10))
            futures += [client.submit(_drawn, job[0], futures[0], *job[1:], pure=False)
                        for job in jobs]
            return client.gather(futures[1:])
        except Exception as e:  # drawn here instead
            if interrupted(e):
                raise
        finally:
            with contextlib.suppress(Exception):
                client.cancel(futures)
    return [_drawn(*job[:1], d, *job[1:]) for job in jobs]


def waterfall(d: Any):
    """The held-out error of the fitted start, after each added effect and of the final
    model as bars, the noise floor dashed; a comparison's one model as one bar."""
    hist = d.history()
    if getattr(d, "compared", False):
        fig, ax = plt.subplots(figsize=(WIDTH_IN, 2.2))
        ax.barh(0, 100 * hist[-1][1], color=MODEL_COLORS["model"], height=0.5)
        ax.axvline(100 * d.noise_floor, color="tab:red", ls="--", label="noise floor")
        ax.set_yticks([0], ["model"])
        ax.set_ylim(-0.6, 0.6)
        ax.set_xlabel("held-out error of the compared model (NRMS, %)")
        ax.legend(fontsize=LEGEND_FONTSIZE, loc="lower right")
        style_axes(ax)
        fig.tight_layout()
        return fig
    fig, ax = plt.subplots(figsize=(WIDTH_IN, 4.2))
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
    ax.set_title("error waterfall", fontsize=LABEL_FONTSIZE)
    ax.legend(fontsize=LEGEND_FONTSIZE)
    style_axes(ax)
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
    coherence beneath; the start and final models overlaid, the measured trace on top,
    drawn where its coherence is at least `COHERENCE_MIN` and the command's power within
    `COMMAND_POWER_MIN` of its peak (`vtable.viz.figures.supported`)."""
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
    _, gxx = scipy.signal.welch(x, fs=run.fs, nperseg=n, noverlap=round(0.5 * n))  # as tm's
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
               f"Δf {tm.resolution_hz:.3g} Hz", min_coherence=COHERENCE_MIN,
        command_psd=gxx[sel])


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
    fig, ax = plt.subplots(2 * len(rows), 1, sharex=True,
                           figsize=(WIDTH_IN, 3.0 * len(rows) + 1.2),
                           gridspec_kw={"height_ratios": [2, 1] * len(rows)})
    for k, (g, y, yhat) in enumerate(rows):
        unit = display.unit_for(GROUP_UNITS[g], display.run_family(run), run.units.values())
        shown = PRETTY.get(unit, unit)
        ym, yh = display.from_si(y, unit), display.from_si(yhat, unit)
        a, r = ax[2 * k], ax[2 * k + 1]
        a.plot(t, ym, "k-", lw=MEASURED_LW * 0.8, label="measured", zorder=MEASURED_Z)
        a.plot(t, yh, color=MODEL_COLORS[final], lw=MODEL_LW, alpha=MODEL_ALPHA,
               label=f"{final}: fit {fit_percent(y, yhat):.1f} %", zorder=MODEL_Z)
        a.set_ylabel(f"{g}\n({shown})")
        a.legend(fontsize=LEGEND_FONTSIZE, loc="upper right")
        r.plot(t, yh - ym, color="tab:red", lw=0.8)
        r.set_ylabel(f"residual\n({shown})")
        for x in (a, r):
            x.grid(alpha=0.3)
    ax[-1].set_xlabel(f"time from the run's start (s); held-out segment of {short(run.name)}")
    style_axes(*ax)
    fig.tight_layout()
    return fig


def hysteresis_loops(d: Any, run):
    """Each storey's shear against its drift over the whole of `run` (the run's
    floorK_drift and floorK_shear), measured (on top) and the final model's, up to three
    storeys a row: a yielding storey's loops, an elastic one's line. None when the run has
    no storey channels."""
    storeys = [k for k in range(1, 51) if run.has(f"floor{k}_drift")
               and run.has(f"floor{k}_shear")]
    if not storeys or not d.stages:
        return None
    pred = d.stages[-1].predictions[run.name]
    final = model_stages(d)[-1][0]
    fam = display.run_family(run)
    du = display.unit_for("in", fam, run.units.values())
    fu = display.unit_for("kip", fam, run.units.values())
    cols = min(3, len(storeys))
    rows = -(-len(storeys) // cols)
    fig, ax = plt.subplots(rows, cols, figsize=(WIDTH_IN, 3.8 * rows + 0.6), squeeze=False)
    for a in ax.flat[len(storeys):]:
        a.set_visible(False)
    for a, k in zip(ax.flat, storeys, strict=False):
        u, v = run.channels[f"floor{k}_drift"], run.channels[f"floor{k}_shear"]
        a.plot(display.from_si(u, du), display.from_si(v, fu), "k-", lw=0.6, label="measured",
               zorder=MEASURED_Z)
        if f"floor{k}_drift" in pred and f"floor{k}_shear" in pred:
            a.plot(display.from_si(pred[f"floor{k}_drift"], du),
                   display.from_si(pred[f"floor{k}_shear"], fu), color=MODEL_COLORS[final],
                   lw=MODEL_LW * 0.6, alpha=MODEL_ALPHA, label=final, zorder=MODEL_Z)
        a.set_xlabel(f"storey {k} drift ({du})")
        a.set_ylabel(f"storey {k} shear ({fu})")
        a.grid(alpha=0.3)
        a.legend(fontsize=LEGEND_FONTSIZE)
        style_axes(a)
    fig.suptitle(f"{short(run.name)}: storey shear against drift", fontsize=LABEL_FONTSIZE)
    fig.tight_layout()
    return fig


def _plus(effects) -> str:
    return (" + " + ", ".join(effects)) if effects else ""


def wording(d: Any) -> dict[str, str]:
    """The report's words for what it draws: a diagnosis's start and final models (one,
    when nothing was added), or a comparison's (`compared`) one model, and what the linear
    model holds (`vtable.diagnose.prose.linear_model`: the specimen, or the bare platen)."""
    compared = bool(getattr(d, "compared", False))
    held = f"linear {linear_model(d.runs)}{_plus(d.start_effects)}"
    if compared:
        return {"models": "the model", "tf": "measured and the model", "final": "the model",
                "error": "the error", "model": f"Model: {held}, fitted on the training "
                                               "segments with the base calibrated."}
    two = len(d.stages) > 1
    return {"models": "the start and final models" if two else "the model",
            "tf": "measured, start and final models" if two else "measured and the model",
            "final": "final model", "error": "the final error",
            "model": f"Starting model: {held}."}


def bode_caption(models: str) -> str:
    """What the Bode plots show and leave out (`vtable.viz.figures.supported`)."""
    return (f"<p>Each figure: H1 of a channel group over the command h_span (magnitude in dB "
            f"with its ±1σ band, unwrapped phase, coherence γ² beneath), {models} drawn wide "
            f"beneath the measured estimate (black, on top). The measured estimate is left "
            f"out where its coherence is below {COHERENCE_MIN:g} (more than half of the "
            "output's power there is not linearly related to the command: noise, "
            "nonlinearity or leakage) or where the command's power is below "
            f"{COMMAND_POWER_MIN:.1%} of its peak (outside the command's band, where H1 "
            "divides noise by almost nothing; the models are left out there too).</p>")


def write_report(d: Any, path: str | Path) -> Path:
    """Write the HTML report of `d` to `path`."""
    e = html.escape
    w = wording(d)
    compared = bool(getattr(d, "compared", False))
    start = "—" if d.start_error is None else f"{d.start_error:.2%}"
    final = "—" if d.final_error is None else f"{d.final_error:.2%}"
    errors = (f"Held-out error {final}" if compared else
              f"Held-out error {start} → {final}") + f"; noise floor {d.noise_floor:.2%}."
    u = d.unexplained
    title = html.escape(d.title)
    parts = [f"<html><head><meta charset='utf-8'><title>{title}</title>"
             f"<style>{STYLE}</style></head><body>",
             f"<h1>{title}</h1>",
             *([f"<p style='font-size:1.2em'><b>{e(d.headline)}</b></p>"] if d.headline else []),
             *(["<ul>" + "".join(f"<li>{e(f['what'])}"
                                 + (f" <i>({e(', '.join(f['runs']))})</i>" if f['runs'] else "")
                                 + f"<br>→ {e(f['action'])}</li>" for f in d.findings)
                + "</ul>"] if d.findings else []),
             f"<details><summary>Verdict (the statistics)</summary><p>{e(d.verdict)}</p>"
             "</details>",
             "<p><b>Unexplained:</b> " + (e(f"none: {w['error']} is consistent with the "
                                             "noise floor") if u is None else
                                           e(f"{w['error']} is {u['ratio_to_floor']:.1f} x "
                                             f"the noise floor; {u['where']}")) + "</p>",
             f"<p>Runs: {e(', '.join(r.name for r in d.runs))}. {e(w['model'])} "
             f"{errors}</p>"]
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
    jobs: list[tuple] = []  # every figure, drawn together (`_drawn_all`)
    if d.history():
        jobs.append((waterfall,))
    if d.stages and d.comparison_start is not None and d.comparison_final is not None:
        for i, _ in enumerate(d.runs):
            jobs += [(tf_overlay, g, _Run(i))
                     for g in ("table displacement", "pitch", "structure acceleration")]
        jobs += [(time_histories, _Run(i)) for i, _ in enumerate(d.runs)]
        jobs += [(hysteresis_loops, _Run(i)) for i, _ in enumerate(d.runs)]
    drawn = dict(zip(range(len(jobs)), _drawn_all(d, jobs), strict=True))
    pngs = {(job[0], *job[1:]): drawn[k] for k, job in enumerate(jobs)}

    def imgs(*keys) -> list[str]:
        return [_tag(pngs[k]) for k in keys if pngs.get(k) is not None]

    if d.history():
        parts += ["<h2 id='waterfall'>" + ("Held-out error" if compared else "Error waterfall")
                  + "</h2>", *imgs((waterfall,))]
    for i, r in enumerate(d.rounds, 1):
        parts.append(f"<h2>Round {i}: {'added ' + e(r.added) if r.added else 'nothing added'}"
                     "</h2><table><tr><th>rank</th><th>effect</th><th>held-out error</th>"
                     "<th>evidence</th><th>fit at a bound</th></tr>")
        for k, c in enumerate(r.ranking, 1):
            parts.append(f"<tr><td>{k}</td><td>{e(c.effect)}</td><td>{c.error_after:.2%}</td>"
                         f"<td>{e(c.evidence)}</td><td>{e('; '.join(c.flags))}</td></tr>")
        parts.append("</table>")
    if d.stages and d.comparison_start is not None and d.comparison_final is not None:
        parts += [f"<h2 id='tf'>Transfer functions: {w['tf']}</h2>",
                  bode_caption(w["models"])]
        runs = [_Run(i) for i, _ in enumerate(d.runs)]
        parts += imgs(*((tf_overlay, g, r) for r in runs
                        for g in ("table displacement", "pitch", "structure acceleration")))
        parts.append(f"<h2 id='time'>Time histories: measured and {w['final']} (held out)</h2>")
        parts += imgs(*((time_histories, r) for r in runs))
        loops = imgs(*((hysteresis_loops, r) for r in runs))
        if loops:
            parts.append("<h2 id='loops'>Hysteresis loops: storey shear against drift "
                         f"(measured and {w['final']})</h2>")
            parts += loops
        parts.append("<h2>Error per channel group (held out, NRMS)</h2><table><tr><th>run</th>"
                     "<th>group</th>" + ("<th>model</th>" if compared else
                                         "<th>start</th><th>final</th>") + "</tr>")
        for run, errs in d.comparison_start.per_run.items():
            for g, v in errs.items():
                f = d.comparison_final.per_run[run].get(g, float("nan"))
                cells = f"<td>{f:.2%}</td>" if compared else f"<td>{v:.2%}</td><td>{f:.2%}</td>"
                parts.append(f"<tr><td>{e(short(run))}</td><td>{e(g)}</td>{cells}</tr>")
        parts.append("</table>")
    parts.append("</body></html>")
    return write_text(path, "\n".join(parts))
