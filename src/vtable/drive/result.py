"""What a drive computation returns (`vtable.drive.compensate`): the drive and the
baselines played on the model (`Played`) with their metrics — the effective motion's NRMS
and peak error against the target, the worst error of its 5 %-damped response spectrum,
the specimen's peak, the drive's use of the table's limits — and `DriveResult`, which
prints, draws and writes itself (`report`, `plot`, `write_report`, `to_json`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vtable.drive.target import Target
from vtable.jsonable import jsonable
from vtable.signals.spectra import response_spectrum

#: the response spectrum's frequencies (Hz) and damping (issue 20: 0.5-20 Hz, 5 %)
SPECTRUM_HZ = (0.5, 20.0)
SPECTRUM_DAMPING = 0.05


def nrms(e: np.ndarray, ref: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e**2)) / np.sqrt(np.mean(ref**2)))


def acceleration(x: np.ndarray, fs: float) -> np.ndarray:
    """Second derivative by central differences (m/s² from m)."""
    return np.gradient(np.gradient(x, 1 / fs), 1 / fs)


def spectrum_error(y: np.ndarray, target: np.ndarray, fs: float) -> dict[str, float]:
    """The 5 %-damped pseudo-acceleration spectrum of `y` against the target's over
    0.5-20 Hz: the worst ratio error and where."""
    f = np.geomspace(*SPECTRUM_HZ, 60)
    a_y, a_t = (response_spectrum(acceleration(v, fs), 1 / fs, 1 / f, SPECTRUM_DAMPING).psa
                for v in (y, target))
    r = a_y / a_t - 1
    i = int(np.argmax(np.abs(r)))
    return {"worst_ratio_error": float(r[i]), "at_hz": float(f[i])}


@dataclass
class Played:
    """A drive played on the model and how the specimen's base felt it."""

    name: str
    drive: np.ndarray
    channels: dict[str, np.ndarray] = field(repr=False)
    metrics: dict[str, Any]


@dataclass
class DriveResult:
    """`compensate`'s result: the drive, what the model predicts when it is played, the
    iteration history and the baselines, with the settings used (`to_json`, `report`,
    `plot`)."""

    objective: str
    target: Target
    fs: float
    drive: Played
    baselines: list[Played]
    history: list[float]
    settings: dict[str, float]
    h: float
    notes: list[str] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)
    #: the model's |H| from the drive to the objective at the table's band
    #: ("table_band") and at the end of the correction band ("correction_band")
    response: dict[str, float] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """The result as `vtable drive --json` writes it (docs/drive.md): every row with
        the same figures, null where a row has none (the elongation is not compared with
        the target; the specimen's peak ratio needs an SDOF specimen)."""
        return jsonable({"format": "vtable-drive/1", "objective": self.objective,
                         "target": self.target.name, "fs_hz": self.fs,
                         "effective_height_m": self.h, "settings": self.settings,
                         "table_response": self.response,
                         "iterations": len(self.history) - 1,
                         "history_nrms": self.history, "drive": _row(self.drive.metrics),
                         "baselines": {b.name: _row(b.metrics) for b in self.baselines},
                         "notes": self.notes})

    def report(self) -> str:
        out = [f"drive for {self.target.name} ({self.target.t[-1]:.1f} s), objective "
               f"{'x_t + θh' if self.objective == 'effective' else 'x_t'} "
               f"(h = {self.h / 0.0254:.1f} in); λ {self.settings['regularisation']:g}, "
               f"cap {self.settings['cap']:g}; {len(self.history) - 1} iterations on the "
               "model, NRMS " + " -> ".join(f"{100 * e:.2f} %" for e in self.history)]
        out.append(f"  {'':28}{'NRMS':>8}{'peak err':>10}{'spectrum':>10}{'at Hz':>7}"
                   f"{'specimen':>10}{'drive pk':>10}{'stroke':>8}{'vel':>6}{'force':>7}")
        for p in (self.drive, *self.baselines):
            m = p.metrics
            sp = m.get("spectrum", {})
            spec = m.get("specimen_peak_ratio")
            out.append(f"  {p.name:28}{_pct(m.get('nrms')):>8}{_pct(m.get('peak_error')):>10}"
                       f"{_pct(sp.get('worst_ratio_error')):>10}"
                       f"{_hz(sp.get('at_hz')):>7}"
                       f"{'—' if spec is None else f'{spec:.3f}':>10}"
                       f"{m['drive_peak_in']:>8.3f} in"
                       + "".join(f"{_use(m.get('limit_use', {}).get(k)):>{w}}"
                                 for k, w in (("displacement", 8), ("velocity", 6),
                                              ("force", 7))))
        out.append("  spectrum: the worst error of the 5 %-damped PSA of x_eff over the "
                   "target's, 0.5-20 Hz; specimen: its predicted peak drift over its "
                   "fixed-base peak under the target; stroke, vel, force: the drive's "
                   "peaks as shares of the table's limits")
        if self.amplification_text():
            out.append(f"  {self.amplification_text()}")
        out += [f"  note: {n}" for n in self.notes]
        out += [f"wrote {f}" for f in self.files]
        return "\n".join(out)

    def amplification_text(self) -> str:
        """The drive's amplification of the target in words (`capped_near_fixed_base`'s
        figures), for the printed and the HTML report; '' when there are none."""
        amp = self.drive.metrics.get("amplification")
        if not amp:
            return ""
        cap = self.settings["cap"]
        near = ""
        if "near_fixed_base" in amp:
            where = (f"; near the specimen's fixed-base frequency (±{amp['window']:.0%}, "
                     "where the cap applies) ")
            if amp["near_fixed_base"] is None:
                near = where + "— (the target holds no content there)"
            else:
                held = (f", held to the cap {cap:g} (it was "
                        f"{amp['near_fixed_base_uncapped']:.1f}; within 10 %)"
                        if amp["capped"] and amp["held"] else
                        f", above the cap {cap:g}: it could not be held to it"
                        if amp["capped"] else f", within the cap {cap:g}")
                near = (where + f"{amp['near_fixed_base']:.1f} at "
                        f"{amp['near_fixed_base_hz']:.2f} Hz{held}")
        return (f"the drive's amplification of the target (|D|/|T| of the drive as written, "
                f"after the cap; where the target has content, its acceleration power within "
                f"{amp['content_db']:g} dB of its largest): largest {amp['largest']:.1f} at "
                f"{amp['at_hz']:.1f} Hz (the cap applies near the specimen's fixed-base "
                f"frequencies only){near}")

    def psa(self, x: np.ndarray, f: np.ndarray) -> np.ndarray:
        """The 5 %-damped pseudo-acceleration spectrum (m/s²) of displacement x at f (Hz)."""
        return response_spectrum(acceleration(x, self.fs), 1 / self.fs, 1 / f,
                                 SPECTRUM_DAMPING).psa

    def plot(self, png: str | Path) -> Path:
        """Target, predicted effective motion and the drive against time; their 5 %
        response spectra beneath."""
        from vtable.viz.figures import drive_png

        p = drive_png(png, self, self.psa)
        self.files.append(Path(p))
        return Path(p)

    def write_report(self, path: str | Path) -> Path:
        """The HTML report (`vtable.viz.drive_report`)."""
        from vtable.viz.drive_report import write_report

        return write_report(self, path, self.psa)


#: the figures of every row of the JSON (null where a row has none)
ROW_KEYS = ("nrms", "peak_error", "specimen_peak_ratio")


def _row(m: dict[str, Any]) -> dict[str, Any]:
    """A row's metrics for the JSON: `ROW_KEYS` and `spectrum`'s two figures always
    present, None (null) where the row has no such figure."""
    sp = m.get("spectrum") or {}
    return {**{k: None for k in ROW_KEYS}, **m,
            "spectrum": {"worst_ratio_error": sp.get("worst_ratio_error"),
                         "at_hz": sp.get("at_hz")}}


def _use(v: float | None) -> str:
    return "—" if v is None else f"{100 * v:.0f}%"


def _hz(v) -> str:
    """A frequency for the table's "at Hz" column: '—' where a row has none."""
    return "—" if v is None or not np.isfinite(v) else f"{v:.2f}"


def _pct(v: float | None) -> str:
    return "—" if v is None else f"{100 * v:.2f}%"
