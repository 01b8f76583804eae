"""One library function per command-line verb: each takes plain arguments, does the work
and returns a typed result (`vtable.results`, `vtable.diagnose.result`) with `to_json()`,
`report()` and, where it draws a figure, `plot()`. The CLI (`vtable.cli`) only parses
arguments, calls one of these and formats the result; a script gets the same results by
calling them.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from vtable.errors import VtableError
from vtable.results import (
    Assessment,
    CampaignIdentification,
    Demo,
    DemoSimulation,
    FrequencyResponse,
    Margins,
    Modes,
    Presets,
    SimulationSummary,
    Study,
    Written,
)

if TYPE_CHECKING:  # the diagnosis is imported when used: it takes seconds to load
    from vtable.diagnose.result import Diagnosis, ModelComparison


# ---- analytical models -------------------------------------------------------------------
def _modes_dict(model) -> dict[str, Any]:
    m = model.modes()
    return {"model": model.title, "stable": model.is_stable(),
            "modes": [{"f_hz": x.f_hz, "damping": x.damping} for x in m.oscillatory],
            "real_roots_per_s": list(m.real_roots)}


def _margins_dict(model, out: str, inp: str) -> dict[str, Any]:
    g = model.margins(out, inp)
    return {"model": model.title, "loop": f"L = H/(1-H), H = {out}/{inp}",
            "gain_margin": g.gain_margin, "phase_margin_deg": g.phase_margin,
            "f_phase_crossover_hz": g.f_phase_crossover, "f_gain_crossover_hz": g.f_gain_crossover}


def modes(config: str) -> Modes:
    """Eigen-modes of a named configuration or a model file (eqs 9.1-9.4)."""
    from vtable.analytic import configs

    model = configs.load(config)
    model.check_stable()
    return Modes(**_modes_dict(model))


def margins(config: str, out: str = "x_t", inp: str = "x_c") -> Margins:
    """Gain and phase margins of L = H/(1-H), H = out/inp."""
    from vtable.analytic import configs

    return Margins(**_margins_dict(configs.load(config), out, inp))


def presets() -> Presets:
    from vtable.analytic import configs

    return Presets(configs.names())


def is_run(path: str) -> bool:
    """Whether `path` names a run (an HDF5 file, or a TOML with a `format` key) rather
    than a model file or a configuration name."""
    from vtable.params.base import read_toml

    p = Path(path)
    if p.suffix in (".h5", ".hdf5"):
        return True
    if p.suffix != ".toml" or not p.is_file():
        return False
    return "format" in read_toml(p)  # model files have no format key


def tf(config: str, out: str = "x_t", inp: str = "x_c", fmin: float = 0.5, fmax: float = 20.0,
       n: int = 40, log: bool = False, nperseg: int | None = None,
       png: str | None = None) -> FrequencyResponse:
    """A frequency response: of a model (at n frequencies), or of a run by H1 with
    coherence (`run_tf`)."""
    if is_run(config):
        return run_tf(config, out, inp, fmin, fmax, nperseg, png)
    from vtable.analytic import configs

    if not (0 < fmin < fmax):
        raise VtableError(f"need 0 < --fmin < --fmax, got {fmin:g}, {fmax:g}")
    if n < 2:
        raise VtableError(f"--n must be at least 2, got {n}")
    model = configs.load(config)
    model.check_stable()
    f = (np.geomspace if log else np.linspace)(fmin, fmax, n)
    H = model.freqresp(f, out, inp)
    r = FrequencyResponse(model.title, out, inp, f, H, f"{model.title}: {out}/{inp}")
    if png:
        r.plot(png)
    return r


def run_tf(path: str, out: str = "x_t", inp: str = "x_c", fmin: float = 0.5,
           fmax: float = 20.0, nperseg: int | None = None,
           png: str | None = None) -> FrequencyResponse:
    """H1 with coherence between two channels of a run, on frames giving >= 8 averages
    (vtable.ident.frames) unless `nperseg` says otherwise; too few averages are warned."""
    from vtable.ident import channels, transfer_function
    from vtable.ident.drive import align
    from vtable.ident.frames import FEWEST_AVERAGES, MIN_AVERAGES, averages, frame_for_averages
    from vtable.runs import read_any

    run = align(read_any(path))
    out = "avg_hdisp" if out == "x_t" else out
    inp = "h_span" if inp == "x_c" else inp
    x, y = run.channel(inp), run.channel(out)
    for name, kind in ((inp, "input"), (out, "output")):
        why = channels.channel_problem(run, name)
        if why:
            raise VtableError(f"{run.name}: {why}: no transfer function with it as the {kind}")
    if not (0 <= fmin < fmax):
        raise VtableError(f"need 0 <= --fmin < --fmax, got {fmin:g}, {fmax:g}")
    n_samples, warnings = len(x), []
    n8 = frame_for_averages(n_samples, MIN_AVERAGES)
    if nperseg is not None:
        if not 16 <= nperseg <= n_samples:
            raise VtableError(f"--nperseg must be between 16 and the run's {n_samples} samples, "
                              f"got {nperseg}")
        n, why = nperseg, "given --nperseg"
    elif n8 is not None:
        n, why = n8, f"the longest power-of-two frame giving >= {MIN_AVERAGES} averages"
    else:
        n = frame_for_averages(n_samples, FEWEST_AVERAGES)
        if n is None:
            raise VtableError(f"{run.name}: {n_samples} samples are too short for a transfer "
                              f"function of {FEWEST_AVERAGES} averages")
        why = f"the record is too short for {MIN_AVERAGES} averages of 64-point frames"
    nd = averages(n_samples, n)
    better = f"; --nperseg {n8} gives {averages(n_samples, n8)}" if n8 and n8 != n else ""
    if nd <= 1:
        warnings.append(f"1 average ({n} of {n_samples} samples): the coherence is 1 by "
                        f"construction and means nothing; the estimate is not averaged{better}")
    elif nd < MIN_AVERAGES:
        warnings.append(f"{nd} averages (< {MIN_AVERAGES}): large random error, coherence "
                        f"biased towards 1{better}")
    est = transfer_function(x, y, run.fs, n)
    sel = (est.f >= fmin) & (est.f <= fmax)
    r = FrequencyResponse(run.name, out, inp, est.f[sel], est.H[sel],
                          f"{run.name}: {out}/{inp} ({nd} averages)", est.coherence[sel],
                          est.averages, n, run.fs / n, why, nd > 1, warnings, list(run.reports))
    if png:
        r.plot(png)
    return r


# ---- measured runs ---------------------------------------------------------------------
def load_effects(files: Sequence[str]) -> list[str]:
    """Register the effects of the user's files; their names."""
    from vtable.effects import load_file

    return [n for f in files for n in load_file(f)]


def effect_names(text: str) -> list[str]:
    """'a, b' -> ["a", "b"], each a registered effect."""
    from vtable.effects.registry import get

    names = [e.strip() for e in text.split(",") if e.strip()]
    for e in names:
        get(e)
    return names


def identify(paths: Sequence[str]) -> CampaignIdentification:
    """The report's identification of every run of one configuration."""
    from vtable.ident.drive import align
    from vtable.ident.report import identify_run
    from vtable.runs import campaign

    return CampaignIdentification([identify_run(align(r)) for r in campaign(paths)])


def compare(paths: Sequence[str], effects: Sequence[str] = (),
            calibrate: str = "") -> ModelComparison:
    """How the model with `effects` fits the runs (fitted on the training segments,
    scored on the held-out ones; the base calibrated as `calibrate` says, see
    `vtable.diagnose.calibration.Calibration.parse`)."""
    from vtable.diagnose.calibration import Calibration
    from vtable.diagnose.model import TableModel
    from vtable.diagnose.result import ModelComparison
    from vtable.ident.drive import align
    from vtable.runs import campaign

    return ModelComparison.of(TableModel(effects, calibration=Calibration.parse(calibrate))
                              .fit([align(r) for r in campaign(paths)]))


def diagnose(paths: Sequence[str], with_: Sequence[str] = (), catalog: Sequence[str] = (),
             max_rounds: int = 4, progress: Callable | None = None, rerun: str | None = None,
             report: str | None = None, calibrate: str = "") -> Diagnosis:
    """The diagnosis loop on the runs; writes the Rerun recording (`rerun`) and the HTML
    report (`report`) asked for (`Diagnosis.plot`, listed in its `files`). Ctrl-C raises
    `DiagnosisInterrupted` carrying the rounds finished (`partial`, `interrupted` true)."""
    from vtable.diagnose.calibration import Calibration
    from vtable.diagnose.engine import Diagnoser
    from vtable.ident.drive import align
    from vtable.runs import campaign

    if max_rounds < 1:
        raise VtableError(f"--max-rounds must be at least 1, got {max_rounds}")
    d = Diagnoser([align(r) for r in campaign(paths)], list(with_), catalog=list(catalog) or None,
                  progress=progress, max_rounds=max_rounds,
                  calibration=Calibration.parse(calibrate)).diagnose()
    d.plot(report=report, rerun=rerun)
    return d


# ---- the virtual table -------------------------------------------------------------------
def simulation_summary(exp) -> dict[str, Any]:
    """Peak table of a virtual-table experiment (report units)."""
    ch = {k: exp.channel(k) for k in exp.run.channels}
    keys = [("h_span", "in"), ("avg_hdisp", "in"), ("pitch_disp", "rad"), ("pitch_acc", "rad/s2"),
            ("acc_n_ne", "g"), ("pot_n_sw", "in"), ("h1_force", "kip"), ("v1_force", "kip"),
            ("p1_stab", "kip")]
    peaks = {k: {"peak": float(np.max(np.abs(ch[k]))), "unit": u} for k, u in keys if k in ch}
    return {"peaks": peaks, "exceedances": [str(e) for e in exp.result.exceedances],
            "files": [str(f) for f in exp.files], "notes": list(exp.notes)}


def simulate(specimen: str = "sdof_frame", kind: str = "random", *,
             duration: float | None = None, band: tuple[float, float] = (0.0, 25.0),
             peak: float | None = None, freq: float = 2.0, seed: int = 0,
             record: str | None = None, valve: str = "linear",
             effects: Sequence[str] = (), out: str | None = None, rerun: str | None = None,
             exaggerate: float = 50.0, table: str = "eerc") -> SimulationSummary:
    """Run a command on the multibody virtual table of `table` (a preset name, or a TOML
    file with a [table] in the run format's keys; `effects`: 'name[:p=v,...]' added to the
    standard table); the peak table, limits and files written."""
    from vtable.effects.registry import parse_spec
    from vtable.params.virtual import virtual_table_for
    from vtable.signals import make_command
    from vtable.sim.experiment import load_specimen, load_table, run_experiment

    eff = dict(parse_spec(e) for e in effects)
    lab = load_table(table)
    vt = virtual_table_for(lab)
    spec = load_specimen(specimen)
    if peak is None and lab.stroke is not None:  # the defaults, within the table's stroke
        default = {"earthquake": 4.0, "pulse": 1.0, "random": 0.25, "sine": 0.1}[kind] \
            if kind in ("earthquake", "pulse", "random", "sine") else None
        if default is not None and default * 0.0254 > 0.5 * lab.stroke:
            peak = 0.5 * lab.stroke / 0.0254
    cmd = make_command(kind, duration=duration, band=tuple(band), peak_in=peak,
                       frequency=freq, seed=seed, record=record)
    exp = run_experiment(spec, cmd, vt=vt, valve=valve, out=out, effects=eff)
    if rerun is not None:
        from vtable.viz.rerun_scene import log_run

        exp.files.append(log_run(exp.run, rerun, exaggeration=exaggerate))
    summary = simulation_summary(exp)
    summary.update({"command": cmd.name, "specimen": spec.title,
                    "duration_s": float(exp.result.t[-1] - exp.result.t[0])})
    return SimulationSummary(**summary)


def export_mjcf(specimen: str, out: str) -> Written:
    from vtable.mjcf.export import export_mjcf as export
    from vtable.sim.experiment import load_specimen

    return Written([Path(f) for f in export(load_specimen(specimen), out)])


def demo(out: str = "vtable-demo", simulate_too: bool = True) -> Demo:
    """The built-in EERC configuration: the hybrid model's coupled modes and margins, the
    peak and notch of x_t/x_c, and the SDOF frame on the virtual table under El Centro."""
    from vtable.analytic import configs

    model = configs.load(configs.DEFAULT)
    model.check_stable()
    f = np.linspace(0.2, 15.0, 2961)
    xt, xe = np.abs(model.freqresp(f, "x_t", "x_c")), np.abs(model.freqresp(f, "x_eff", "x_c"))
    th = np.abs(model.freqresp(f, "theta_h", "x_c"))
    near = f < 5.0
    d = {"configuration": configs.DEFAULT, **_modes_dict(model),
         "margins": _margins_dict(model, "x_t", "x_c"),
         "x_t/x_c": {"peak": float(xt[near].max()),
                     "f_peak_hz": float(f[near][xt[near].argmax()]),
                     "notch": float(xt[near].min()),
                     "f_notch_hz": float(f[near][xt[near].argmin()])},
         "x_eff/x_c notch_hz": float(f[near][xe[near].argmin()]),
         "theta_h/x_c peak_hz": float(f[near][th[near].argmax()])}
    if simulate_too:
        d["simulation"] = _demo_simulation(out)
    return Demo.from_dict(d)


def _demo_simulation(out: str) -> DemoSimulation:
    from vtable.signals import make_command
    from vtable.sim.experiment import load_specimen, run_experiment
    from vtable.studies import response_spectrum
    from vtable.units import to_si
    from vtable.viz.rerun_scene import log_run

    spec = load_specimen("sdof_frame")
    cmd = make_command("earthquake")
    exp = run_experiment(spec, cmd, out=f"{out}/sdof_elcentro")
    exp.files.append(log_run(exp.run, f"{out}/sdof_elcentro.rrd"))
    res = exp.result
    h = exp.result.built.structure_heights[-1]
    x_t, th = res.joint("x"), res.joint("pitch")
    x_s = res.joint("x_s")
    dt = res.t[1] - res.t[0]
    a_eff = res.joint("x", "qacc") + h * res.joint("pitch", "qacc")
    T_s = 1 / spec.frequency
    periods = np.array([T_s])
    ratio = float(response_spectrum(a_eff, dt, periods, 0.05).psa[0]
                  / response_spectrum(res.command_acc, dt, periods, 0.05).psa[0])
    summary = simulation_summary(exp)
    summary.update({
        "command": cmd.name, "duration_s": float(res.t[-1] - res.t[0]),
        "peak_x_t_in": float(np.max(np.abs(x_t)) / to_si(1, "in")),
        "peak_theta_h_in": float(np.max(np.abs(th * h)) / to_si(1, "in")),
        "peak_x_s_in": float(np.max(np.abs(x_s)) / to_si(1, "in")),
        "effective_spectrum_ratio": ratio, "spectrum_period_s": T_s})
    return DemoSimulation(**summary)


# ---- interaction studies -------------------------------------------------------------------
def assess(specimen: str = "sdof_frame", record: str = "elcentro", raw: bool = False,
           out: str = "vtable-assess") -> Assessment:
    """The five models of §9.4 for a specimen and a record: coupled modes, PSV spectra,
    the verdict, and the sweeps of Figs 9.4-9.12 (written as PNGs)."""
    from vtable.signals.processing import process_record
    from vtable.signals.records import load_record
    from vtable.sim.experiment import load_specimen
    from vtable.studies import interaction as ia
    from vtable.viz import figures

    rec = load_record(record)
    if raw:
        acc, dt, label = rec.acc, rec.dt, rec.name
    else:
        cmd = process_record(rec)
        acc, dt, label = cmd.acceleration, cmd.dt, f"{rec.name} (§9.2 processed)"
    res = ia.assess(load_specimen(specimen), acc, dt, label)
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
    return Assessment(res.verdict(), s.title, label,
                      {k: {"f_hz": f, "damping": z} for k, (f, z) in res.modes.items()},
                      res.psv_at_specimen, res.rocking_share, res.elongation,
                      res.compensated_error, [Path(f) for f in files],
                      list(getattr(rec, "notes", ())))


def study(store: str, heights: Sequence[float], records: Sequence[str] = ("elcentro",),
          specimen: str = "sdof_frame", model: str = "virtual", duration: float | None = None,
          scheduler: str | None = None, workers: int = 2) -> Study:
    """A heights x records study on Dask, stored as it runs and resumable."""
    from vtable.studies.scaleout import height_record_study, run_study

    common: dict[str, Any] = {"specimen": specimen}
    if duration is not None or model == "virtual":
        common["duration"] = duration if duration is not None else 4.0
    s = height_record_study(list(heights), list(records), model, **common)
    return Study(store, model, run_study(s, store, scheduler=scheduler, n_workers=workers))
