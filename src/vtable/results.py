"""What the verbs return (python-control's `*_response` pattern): typed results, each with
`to_json()` (the plain JSON `--json` writes, the same for every verb), `report()` (the
text the command line prints) and, where the verb draws a figure, `plot()`. A result that
wrote files lists them in `files`.

The diagnosis's results live beside it (`vtable.diagnose.result`: `Diagnosis`,
`ModelComparison`); the analytical models', the virtual table's and the studies' are here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from vtable import display, units
from vtable.jsonable import jsonable

if TYPE_CHECKING:  # the CLI starts without scipy.signal
    from vtable.ident.result import Identification


class Result(Protocol):
    """What every verb returns."""

    files: list[Path]

    def to_json(self) -> dict[str, Any]: ...

    def report(self) -> str: ...


def _names(files: list[Path]) -> list[str]:
    return [str(f) for f in files]


# ---- analytical models -------------------------------------------------------------------
@dataclass
class ModesResult:
    """Eigen-modes of a model (eqs 9.1-9.4): `modes` each {f_hz, damping}, the real roots
    in 1/s."""

    model: str
    stable: bool
    modes: list[dict[str, float]]
    real_roots_per_s: list[float]
    files: list[Path] = field(default_factory=list)
    #: the published modes to print beside these: (source, ((f Hz, damping), ...))
    reference: tuple[str, Any] | None = None

    def to_json(self) -> dict[str, Any]:
        d = {"model": self.model, "stable": self.stable, "modes": self.modes,
             "real_roots_per_s": self.real_roots_per_s}
        if self.reference is not None:
            src, modes = self.reference
            d["reference"] = {"source": src,
                              "modes": [{"f_hz": f, "damping": z} for f, z in modes]}
        return jsonable(d)

    def report(self) -> str:
        out = [f"{self.model}: {'stable' if self.stable else 'UNSTABLE'}",
               f"  {'mode':>4}  {'f (Hz)':>9}  {'damping':>8}"]
        ref = dict(enumerate(self.reference[1], 1)) if self.reference else {}
        for i, m in enumerate(self.modes, 1):
            line = f"  {i:>4}  {m['f_hz']:9.4f}  {m['damping']:8.4f}"
            if i in ref:
                line += f"        {self.reference[0]}: {ref[i][0]:.4f} Hz, {ref[i][1]:.4f}"
            out.append(line)
        if self.real_roots_per_s:
            out.append("  real roots (1/s): "
                       + ", ".join(f"{r:.2f}" for r in self.real_roots_per_s))
        return "\n".join(out)


@dataclass
class MarginsResult:
    """Gain and phase margins of the loop L = H/(1-H) (`loop` says which H)."""

    model: str
    loop: str
    gain_margin: float
    phase_margin_deg: float
    f_phase_crossover_hz: float
    f_gain_crossover_hz: float
    files: list[Path] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return jsonable({"model": self.model, "loop": self.loop,
                         "gain_margin": self.gain_margin,
                         "phase_margin_deg": self.phase_margin_deg,
                         "f_phase_crossover_hz": self.f_phase_crossover_hz,
                         "f_gain_crossover_hz": self.f_gain_crossover_hz})

    def report(self) -> str:
        gm = (f"  gain margin  {self.gain_margin:.4g}   at {self.f_phase_crossover_hz:.3f} Hz"
              if np.isfinite(self.gain_margin) else
              "  gain margin  none: the phase of L never reaches -180 deg (0.001-1000 Hz)")
        pm = (f"  phase margin {self.phase_margin_deg:.2f} deg at "
              f"{self.f_gain_crossover_hz:.3f} Hz" if np.isfinite(self.phase_margin_deg) else
              "  phase margin none: |L| never reaches 1 (0.001-1000 Hz): the loop gain is "
              "below unity everywhere")
        return "\n".join([f"{self.model}: {self.loop}", gm, pm])


@dataclass
class FrequencyResponse:
    """A frequency response `H` = output/input at `f_hz`: of a model, or of a run by H1
    (then with its coherence, the averages, the frame and what was warned)."""

    model: str
    output: str
    input: str
    f_hz: np.ndarray
    H: np.ndarray
    title: str = ""  # the figure's
    coherence: np.ndarray | None = None  # a run's
    averages: int | None = None
    nperseg: int | None = None
    resolution_hz: float | None = None
    frame: str = ""
    coherence_meaningful: bool = True
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    png: str | None = None  # the figure written (`plot`), as named
    files: list[Path] = field(default_factory=list)

    @property
    def of_run(self) -> bool:
        return self.coherence is not None

    def to_json(self) -> dict[str, Any]:
        d: dict[str, Any] = {"model": self.model, "output": self.output, "input": self.input,
                             "f_hz": self.f_hz.tolist(), "magnitude": np.abs(self.H).tolist(),
                             "phase_deg": np.degrees(np.angle(self.H)).tolist()}
        if self.of_run:
            d.update({"coherence": self.coherence.tolist(), "averages": self.averages,
                      "nperseg": self.nperseg, "resolution_hz": self.resolution_hz,
                      "frame": self.frame,
                      "coherence_meaningful": self.coherence_meaningful,
                      "warnings": self.warnings, "notes": self.notes})
        if self.png:
            d["png"] = self.png
        return jsonable(d)

    def plot(self, png: str | Path) -> Path:
        """The Bode plot (`vtable.viz.figures.bode_figure`: dB on log frequency,
        unwrapped phase; a run's meaningful coherence beneath and its ±1σ band from the
        averages) to a PNG file."""
        # on use, for start-up: matplotlib takes ~0.9 s, and every verb imports this
        # module for its results' to_json() and report() (`vtable presets` too)
        from vtable.viz.figures import transfer_function_png

        run = self.of_run and self.coherence_meaningful
        transfer_function_png(png, self.f_hz, self.H, self.coherence if run else None,
                              self.title, averages=self.averages if run else None,
                              magnitude_label=f"|{self.output}/{self.input}| (dB)")
        self.png = str(png)
        self.files.append(Path(png))
        return Path(png)

    def report(self) -> str:
        run, n = self.of_run, self.averages
        out = [f"{self.model}: {self.output}/{self.input}"
               + (f" (H1, {n} average{'s' * (n != 1)} of {self.nperseg}-point frames, Δf "
                  f"{self.resolution_hz:.3g} Hz: {self.frame})" if run else "")]
        out += [f"  note: {n}" for n in self.notes]
        out += [f"  ⚠ {w}" for w in self.warnings]
        coh = self.coherence
        show = run and self.coherence_meaningful
        out.append(f"  {'f (Hz)':>9}  {'|H|':>10}  {'phase (deg)':>11}"
                   + ("  coherence" if run else ""))
        for i, (f, m, p) in enumerate(zip(self.f_hz, np.abs(self.H),
                                          np.degrees(np.angle(self.H)), strict=True)):
            out.append(f"  {f:9.3f}  {m:10.4g}  {p:11.2f}"
                       + ((f"  {coh[i]:9.3f}" if show else f"  {'—':>9}") if run else ""))
        if self.png:
            out.append(f"  wrote {self.png}")
        return "\n".join(out)


@dataclass
class Presets:
    """The named configurations."""

    configurations: list[str]
    files: list[Path] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return {"configurations": list(self.configurations)}

    def report(self) -> str:
        return "\n".join(self.configurations)


@dataclass
class Written:
    """Files a verb wrote (`export-mjcf`: the MJCF model and its meshes)."""

    files: list[Path]

    def to_json(self) -> dict[str, Any]:
        return {"files": _names(self.files)}

    def report(self) -> str:
        return "wrote " + ", ".join(_names(self.files))


@dataclass
class CampaignIdentification:
    """The report's identification of every run of one configuration (`runs`: one
    `vtable.ident.result.Identification` each, from `vtable.ident.report.identify_run`)."""

    runs: list[Identification]
    files: list[Path] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return jsonable({"format": "vtable-identification/1",
                         "runs": [r.to_json() for r in self.runs]})

    def report(self) -> str:
        return "\n".join(r.report() for r in self.runs)


# ---- the virtual table -------------------------------------------------------------------
def _displayed(peaks: dict[str, dict[str, Any]], fam: str,
               declared: dict[str, str] | None = None) -> dict[str, dict[str, Any]]:
    """Peaks (in their report units) in the units of the display family `fam`, each
    channel in its run file's unit (`declared`) when that is of the family."""
    if fam != "metric":
        return peaks
    out = {}
    for k, v in peaks.items():
        own = (declared or {}).get(k)
        value, unit = display.shown(units.to_si(v["peak"], v["unit"]), v["unit"], fam,
                                    [own] if own else ())
        out[k] = {"peak": float(value), "unit": unit}
    return out


def _peak_lines(peaks: dict[str, dict[str, Any]]) -> list[str]:
    return [f"  {'channel':<12} {'peak':>10}"] + [
        f"  {k:<12} {v['peak']:10.4g} {v['unit']}" for k, v in peaks.items()]


@dataclass
class SimulationSummary:
    """A run on the virtual table: the peak of each channel (report units), the limits
    exceeded, the files written and what was noted."""

    peaks: dict[str, dict[str, Any]]
    exceedances: list[str]
    files: list[Path]
    notes: list[str]
    command: str
    specimen: str
    duration_s: float
    chosen: list[str] = field(default_factory=list)  # the defaults fitted to the table
    display: str = "imperial"  # the units the report shows ("metric": mm, m/s², kN)
    limits_shown: list[str] | None = None  # the exceedances in the `display` units
    shown_units: dict[str, str] = field(default_factory=dict)  # the run file's units

    def __post_init__(self) -> None:
        self.files = [Path(f) for f in self.files]

    def to_json(self) -> dict[str, Any]:
        return jsonable({"peaks": self.peaks, "exceedances": self.exceedances,
                         "files": _names(self.files), "notes": self.notes,
                         "command": self.command, "specimen": self.specimen,
                         "duration_s": self.duration_s, "chosen": self.chosen})

    def report(self) -> str:
        out = [f"{self.specimen}: {self.command}, {self.duration_s:.2f} s"]
        out += [f"  {c}" for c in self.chosen]
        out += [f"  note: {n}" for n in self.notes]
        out += _peak_lines(_displayed(self.peaks, self.display, self.shown_units))
        limits = self.exceedances if self.limits_shown is None else self.limits_shown
        out += [f"  limit: {e}" for e in limits]
        if self.files:
            out.append("  wrote " + ", ".join(_names(self.files)))
        return "\n".join(out)


@dataclass
class DemoSimulation:
    """The demo's run (the SDOF frame under El Centro): the peaks, and the table's,
    pitch's and structure's peak motion and the effective-motion spectrum ratio."""

    peaks: dict[str, dict[str, Any]]
    exceedances: list[str]
    files: list[Path]
    notes: list[str]
    command: str
    duration_s: float
    peak_x_t_in: float
    peak_theta_h_in: float
    peak_x_s_in: float
    effective_spectrum_ratio: float
    spectrum_period_s: float

    def __post_init__(self) -> None:
        self.files = [Path(f) for f in self.files]

    def to_json(self) -> dict[str, Any]:
        return jsonable({"peaks": self.peaks, "exceedances": self.exceedances,
                         "files": _names(self.files), "notes": self.notes,
                         "command": self.command, "duration_s": self.duration_s,
                         "peak_x_t_in": self.peak_x_t_in,
                         "peak_theta_h_in": self.peak_theta_h_in,
                         "peak_x_s_in": self.peak_x_s_in,
                         "effective_spectrum_ratio": self.effective_spectrum_ratio,
                         "spectrum_period_s": self.spectrum_period_s})

    def report(self) -> str:
        out = [f"\nvirtual table (MuJoCo + servo controllers): {self.command}, "
               f"{self.duration_s:.1f} s, §9.2 processing (length 3.2801, time 1.811, 4 in)"]
        out += _peak_lines(self.peaks)
        out.append(f"  table x_t {self.peak_x_t_in:.3f} in, pitch θh "
                   f"{self.peak_theta_h_in:.3f} in, structure x_s {self.peak_x_s_in:.3f} in")
        out.append(f"  effective-motion spectrum ratio PSA(x_t + hθ)/PSA(command) at the "
                   f"fixed-base period {self.spectrum_period_s:.3f} s, 5 %: "
                   f"{self.effective_spectrum_ratio:.3f}")
        out += [f"  limit: {e}" for e in self.exceedances]
        if self.files:
            out.append("  wrote " + ", ".join(_names(self.files)))
        return "\n".join(out)


@dataclass
class Demo:
    """The built-in EERC configuration: the hybrid model's coupled modes and margins, the
    peak and notch of x_t/x_c, the notch of x_eff/x_c, the peak of θh/x_c, and the demo's
    run (`simulation`, unless left out)."""

    configuration: str
    modes: ModesResult
    margins: MarginsResult
    x_t: dict[str, float]  # x_t/x_c: peak, f_peak_hz, notch, f_notch_hz
    x_eff_notch_hz: float
    theta_h_peak_hz: float
    simulation: DemoSimulation | None = None

    @property
    def files(self) -> list[Path]:
        return self.simulation.files if self.simulation is not None else []

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Demo:
        """From the dictionary `to_json` gives (before JSON)."""
        modes = ModesResult(**{k: d[k] for k in ("model", "stable", "modes", "real_roots_per_s")})
        if "reference" in d:
            r = d["reference"]
            modes.reference = (r["source"], [(m["f_hz"], m["damping"]) for m in r["modes"]])
        return cls(d["configuration"], modes, MarginsResult(**d["margins"]), d["x_t/x_c"],
                   d["x_eff/x_c notch_hz"], d["theta_h/x_c peak_hz"], d.get("simulation"))

    def to_json(self) -> dict[str, Any]:
        d = {"configuration": self.configuration, **self.modes.to_json(),
             "margins": self.margins.to_json(), "x_t/x_c": self.x_t,
             "x_eff/x_c notch_hz": self.x_eff_notch_hz,
             "theta_h/x_c peak_hz": self.theta_h_peak_hz}
        if self.simulation is not None:
            d["simulation"] = self.simulation.to_json()
        return jsonable(d)

    def report(self) -> str:
        p = self.x_t
        out = ["vtable demo: the SDOF braced frame (68 kips, 219 in) on the EERC table",
               "hybrid model, report Table 9.1 (horizontal servo loop + rocking "
               "spring/dashpot)\n", self.modes.report(), "", self.margins.report(),
               f"\ntable motion x_t/x_c: peak {p['peak']:.2f} at {p['f_peak_hz']:.2f} Hz, "
               f"notch {p['notch']:.2f} at {p['f_notch_hz']:.2f} Hz",
               f"effective motion (x_t + θh)/x_c: notch at {self.x_eff_notch_hz:.2f} Hz "
               f"(fixed-base 2.87 Hz); pitch θh/x_c peaks at {self.theta_h_peak_hz:.2f} Hz"]
        if self.simulation is not None:
            out.append(self.simulation.report())
        return "\n".join(out)


# ---- interaction studies -----------------------------------------------------------------
@dataclass
class AssessmentResult:
    """The five models of §9.4 for a specimen and a record: the verdict, the coupled modes
    (model -> f_hz, damping), the PSV at the specimen's period (m/s), the rocking share,
    the time elongation, the compensated error, and the figures written."""

    verdict: str
    specimen: str
    record: str
    modes: dict[str, dict[str, float]]
    psv_at_specimen_period_m_s: dict[str, float]
    rocking_share: float
    time_elongation: float
    compensated_error: float
    files: list[Path]
    notes: list[str]
    #: a yielding specimen's ductility and residual drift, fixed base and on the table,
    #: across the swept periods (`vtable.studies.yielding.DuctilitySweep`)
    yielding: Any = None

    def to_json(self) -> dict[str, Any]:
        return jsonable({"verdict": self.verdict, "specimen": self.specimen,
                         "record": self.record, "modes": self.modes,
                         "psv_at_specimen_period_m_s": self.psv_at_specimen_period_m_s,
                         "rocking_share": self.rocking_share,
                         "time_elongation": self.time_elongation,
                         "compensated_error": self.compensated_error,
                         **({"yielding": self.yielding.to_json()} if self.yielding else {}),
                         "files": _names(self.files), "notes": self.notes})

    def report(self) -> str:
        out = [f"note: {n}" for n in self.notes]
        out.append(self.verdict)
        if self.yielding is not None:
            y = self.yielding
            out.append(f"yielding ({y.held} as declared): ductility and residual drift, fixed "
                       "base / on the table")
            out.append(f"{'T s':>6s} {'mu fixed':>9s} {'mu table':>9s} {'change':>7s} "
                       f"{'residual fixed':>15s} {'residual table':>15s}")
            for T, mf, mt, rf, rt in zip(y.periods, y.ductility_fixed, y.ductility_table,
                                         y.residual_fixed, y.residual_table, strict=True):
                out.append(f"{T:6.3f} {mf:9.2f} {mt:9.2f} {100 * (mt / mf - 1):+6.0f} % "
                           f"{rf / 0.0254:+12.3f} in {rt / 0.0254:+12.3f} in")
        out.append("wrote " + ", ".join(_names(self.files)))
        return "\n".join(out)


@dataclass
class StudyResult:
    """A heights x records study: its store, the model (virtual or analytic) and each
    point's result (key -> what `vtable.studies.scaleout.run_study` stored)."""

    store: str
    model: str
    points: dict[str, dict[str, Any]]
    files: list[Path] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return jsonable({"store": self.store, "model": self.model, "points": self.points})

    def report(self) -> str:
        out = [f"{len(self.points)} points in {self.store} ({self.model})"]
        for k, r in self.points.items():
            if self.model == "virtual":
                ratio = " ".join(f"{x:.2f}" for x in r["psa_ratio"])
                out.append(f"  {k:14s} h {r['height_in']:6.0f} in  peak θ "
                           f"{1e3 * r['peaks_si']['pitch_disp']:.3f} mrad  PSA(x_t+hθ)/PSA(x_c) "
                           f"at {r['periods_s']} s: {ratio}")
            else:
                f, xi = r["modes"]["hybrid"]
                ps = r["psv_at_specimen"]
                dv = 100 * (ps["hybrid"] / ps["fixed base"] - 1)
                out.append(f"  {k:14s} h {r['height_in']:6.0f} in  hybrid f_c {f:.2f} Hz, ξ_c "
                           f"{100 * xi:.1f} %, PSV vs fixed {dv:+.0f} %")
        return "\n".join(out)
