"""The HTML report of a diagnosis: verdict, what remains unexplained, the notes, the base
calibration, ranking tables with evidence and fit flags, the error waterfall and
transfer-function overlays (matplotlib, embedded PNGs). Every axis names its unit; transfer
functions are shown in the run format's units per inch of command. It renders the stages
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
from vtable.fileio import write_text
from vtable.ident.tf import transfer_function

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


def tf_overlay(d: Any, group: str):
    run = max(d.runs, key=lambda r: len(r.time))
    x = run.channel("h_span")
    y = group_signal(run, group)
    if y is None:
        return None
    n = min(1024, 2 ** int(np.log2(len(x) / 2)))
    unit, per = (display.unit_for(u, display.run_family(run), run.units.values())
                 for u in (GROUP_UNITS[group], "in"))  # the run's own units
    scale = display.from_si(1.0, unit) / display.from_si(1.0, per)  # SI ratio -> unit/per
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(6.5, 4.5))
    tm = transfer_function(x, y, run.fs, n)
    sel = (tm.f > 0.2) & (tm.f <= 30)
    a1.plot(tm.f[sel], scale * np.abs(tm.H[sel]), "k-", lw=1.5, label="measured")
    a2.plot(tm.f[sel], np.degrees(np.angle(tm.H[sel])), "k-", lw=1.5)
    for label, stage, style in (("start model", d.stages[0], "tab:red"),
                                ("final model", d.stages[-1], "tab:blue")):
        yhat = group_prediction(stage.predictions[run.name], run, group)
        tp = transfer_function(x, yhat, run.fs, n)
        a1.plot(tp.f[sel], scale * np.abs(tp.H[sel]), color=style, ls="--", label=label)
        a2.plot(tp.f[sel], np.degrees(np.angle(tp.H[sel])), color=style, ls="--")
    a1.set_ylabel(f"amplitude ({PRETTY.get(unit, unit)}/{per})")
    a2.set_ylabel("phase (deg)")
    a2.set_xlabel("frequency (Hz)")
    a1.set_title(f"{group} / command h_span, {short(run.name)}")
    a1.legend()
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
    parts = ["<html><head><meta charset='utf-8'><title>vtable diagnosis</title>"
             "<style>body{font-family:sans-serif;max-width:60em;margin:auto}"
             "td,th{padding:2px 8px;border-bottom:1px solid #ddd}</style></head><body>",
             "<h1>vtable diagnosis</h1>", f"<p><b>Verdict:</b> {e(d.verdict)}</p>",
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
        parts += ["<h2>Error waterfall</h2>",
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
        parts.append("<h2>Transfer functions: measured, start and final models</h2>")
        for g in ("table displacement", "pitch", "structure acceleration"):
            fig = tf_overlay(d, g)
            if fig is not None:
                parts.append(f"<img src='data:image/png;base64,{_png(fig)}'>")
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

