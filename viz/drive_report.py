"""The HTML report of a drive (`vtable drive --report`): what was asked and with which
settings, the figures of the drive and of the three baselines (effective-motion error,
response spectrum, the specimen's peak, the drive's use of the table's limits), the
iteration history, the notes, and the figure of target, prediction and spectra
(`vtable.viz.figures.drive_figure`, embedded as PNG). `r` is a
`vtable.drive.DriveResult`, which draws itself through this module."""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt

from vtable.fileio import write_text
from vtable.viz.figures import drive_figure

STYLE = ("body{font-family:sans-serif;max-width:60em;margin:auto}"
         "td,th{padding:2px 8px;border-bottom:1px solid #ddd;text-align:right}"
         "td:first-child,th:first-child{text-align:left}")


def _band(hz: float | None) -> str:
    return "not declared" if hz is None else f"{hz:g} Hz"


def _pct(v: float | None) -> str:
    return "—" if v is None else f"{100 * v:.2f} %"


def _row(cells: list[str], tag: str = "td") -> str:
    return "<tr>" + "".join(f"<{tag}>{c}</{tag}>" for c in cells) + "</tr>"


def figure_png(r: Any, psa) -> str:
    """The drive's figure as base64 PNG."""
    fig = drive_figure(r, psa)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode()


def write_report(r: Any, path: str | Path, psa) -> Path:
    """Write the HTML report of the drive `r` to `path` (`psa(x, f)`: the pseudo-
    acceleration spectrum of a displacement, for the figure)."""
    e = html.escape
    obj = "x_t + θh (§4.2.2)" if r.objective == "effective" else "x_t"
    title = e(f"vtable drive for {r.target.name}")
    st = r.settings
    parts = [f"<html><head><meta charset='utf-8'><title>{title}</title><style>{STYLE}"
             f"</style></head><body><h1>{title}</h1>",
             f"<p>Objective: the {e(obj)} at the specimen (h = {r.h / 0.0254:.1f} in), "
             f"{r.target.t[-1]:.1f} s at {r.fs:g} Hz. Regularisation λ {st['regularisation']:g}"
             f", cap {st['cap']:g}, corrected up to {st['correction_band_hz']:g} Hz (the "
             f"table's band: {_band(st['table_band_hz'])}). {len(r.history) - 1} iterations on "
             "the model, predicted NRMS " + e(" → ".join(_pct(v) for v in r.history)) + ".</p>",
             "<h2>The drive and the baselines (predicted by the calibrated model)</h2><table>",
             _row(["", "NRMS", "peak error", "PSA worst error", "at Hz", "specimen peak / "
                   "fixed base", "drive peak (in)", "stroke used", "velocity used",
                   "force used"], "th")]
    for p in (r.drive, *r.baselines):
        m = p.metrics
        sp, lim = m.get("spectrum", {}), m.get("limit_use", {})
        spec = m.get("specimen_peak_ratio")
        parts.append(_row([e(p.name), _pct(m.get("nrms")), _pct(m.get("peak_error")),
                           _pct(sp.get("worst_ratio_error")),
                           f"{sp['at_hz']:.2f}" if "at_hz" in sp else "—",
                           "—" if spec is None else f"{spec:.3f}",
                           f"{m['drive_peak_in']:.3f}", _pct(lim.get("displacement")),
                           _pct(lim.get("velocity")), _pct(lim.get("force"))]))
    parts.append("</table><p>PSA: the 5 %-damped pseudo-acceleration spectrum of the "
                 "effective motion over the target's, 0.5–20 Hz. Used: the peak as a share "
                 "of the table's stroke, velocity and actuator capacity.</p>")
    text = r.amplification_text()
    if text:
        parts.append(f"<p>{e(text[0].upper() + text[1:])}.</p>")
    skipped = [b for b in r.baselines if "skipped" in b.metrics]
    for b in skipped:
        parts.append(f"<p>{e(b.name)}: skipped ({e(b.metrics['skipped'])}).</p>")
    if r.notes:
        parts.append("<h2>Notes</h2><ul>" + "".join(f"<li>{e(n)}</li>" for n in r.notes)
                     + "</ul>")
    parts += ["<h2>Target, prediction and spectra</h2>",
              f"<img src='data:image/png;base64,{figure_png(r, psa)}'>", "</body></html>"]
    return write_text(Path(path), "\n".join(parts))
