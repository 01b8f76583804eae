"""The ``vtable`` command line: demo, modes, tf, margins, presets."""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from typing import Any

import numpy as np

from vtable import __version__
from vtable.errors import UnstableError, VtableError
from vtable.jsonable import jsonable

_NUMBER = re.compile(r"[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?", re.ASCII)


def _number(text: str) -> float:
    """A plain decimal number (ASCII digits, optional exponent), finite: Python's float()
    would also take '1_000', full-width or Arabic-Indic digits, 'nan' and 'inf'."""
    if not _NUMBER.fullmatch(text.strip()):
        raise argparse.ArgumentTypeError(f"{text!r} is not a plain number")
    v = float(text)
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{text!r} is too large")
    return v


def _integer(text: str) -> int:
    """A plain integer (ASCII digits)."""
    if not re.fullmatch(r"[+-]?\d+", text.strip(), re.ASCII):
        raise argparse.ArgumentTypeError(f"{text!r} is not a plain integer")
    return int(text)


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, no usage dump
        raise VtableError(f"{message} (see vtable {self.prog.split()[-1]} --help)"
                          if " " in self.prog else f"{message} (see vtable --help)")


_EFFECTS_FROM = "a Python file of your own effects (it calls vtable.effects.register)"


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="vtable", description="Virtual shaking table after UCB/EERC-91/13.")
    p.add_argument("--version", action="version", version=f"vtable {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    def config_cmd(name: str, help: str) -> argparse.ArgumentParser:
        c = sub.add_parser(name, help=help, description=help)
        c.add_argument("config", nargs="?", default="eerc-sdof",
                       help="a named configuration (vtable presets) or a model .toml file "
                            "[default: eerc-sdof]")
        c.add_argument("--json", action="store_true", help="machine-readable output")
        return c

    d = sub.add_parser("demo", help="the built-in EERC configuration: coupled modes, margins, "
                       "and the SDOF frame on the virtual table under El Centro")
    d.add_argument("--json", action="store_true")
    d.add_argument("--out", default="vtable-demo", help="folder for the run and the .rrd "
                   "[vtable-demo]")
    d.add_argument("--no-sim", action="store_true", help="analytical part only")
    sim = sub.add_parser("simulate", help="run a command on the multibody virtual table")
    sim.add_argument("--specimen", default="sdof_frame",
                     help="none, concrete_blocks, sdof_frame, table5_1, table8_1 or a TOML "
                          "file with a [specimen] table [sdof_frame]")
    sim.add_argument("--command", default="random", dest="kind",
                     choices=["random", "sine", "pulse", "earthquake"])
    sim.add_argument("--record", default=None, help="earthquake: elcentro, a .AT2 or .csv "
                     "file, or fema:ID[a|b] [elcentro]")
    sim.add_argument("--duration", type=_number, default=None,
                     help="s [11; an earthquake: the whole processed record]")
    sim.add_argument("--band", type=_number, nargs=2, default=[0.0, 25.0], help="Hz [0 25]")
    sim.add_argument("--peak", type=_number, default=None, help="peak command, in")
    sim.add_argument("--freq", type=_number, default=2.0, help="sine frequency, Hz [2]")
    sim.add_argument("--seed", type=_integer, default=0)
    sim.add_argument("--valve", choices=["linear", "nonlinear"], default="linear",
                     help="linear servovalves (eqs 6.1-6.5) or appendix C valves on H1-H3")
    sim.add_argument("--effect", action="append", default=[], metavar="NAME[:P=V,...]",
                     help="add an effect to the standard table, with parameters in its units "
                          "(e.g. actuator_friction:friction=3); repeatable")
    sim.add_argument("--effects-from", action="append", default=[], metavar="FILE",
                     help=_EFFECTS_FROM)
    sim.add_argument("--out", default=None, help="run file stem (writes STEM.csv, STEM.toml)")
    sim.add_argument("--rerun", default=None, help="write a Rerun recording (.rrd)")
    sim.add_argument("--exaggerate", type=_number, default=50.0,
                     help="pitch/roll exaggeration in the 3D view [50]")
    sim.add_argument("--json", action="store_true")
    ex = sub.add_parser("export-mjcf", help="write the virtual table as MJCF + meshes")
    ex.add_argument("--specimen", default="none")
    ex.add_argument("--out", required=True, help="folder")
    ex.add_argument("--json", action="store_true")
    config_cmd("modes", "eigen-modes: frequency, damping and real roots (eqs 9.1-9.4)")
    m = config_cmd("margins", "gain and phase margins of L = H/(1-H), H = x_t/x_c")
    m.add_argument("--out", default="x_t", help="tracked output [x_t]")
    m.add_argument("--in", dest="inp", default="x_c", help="command input [x_c]")
    t = config_cmd("tf", "frequency response of one output over one input: a model "
                         "configuration, or a measured run (RUN.toml) by H1 with coherence")
    t.add_argument("--out", default="x_t", help="output [x_t]")
    t.add_argument("--in", dest="inp", default="x_c", help="input [x_c]")
    t.add_argument("--fmin", type=_number, default=0.5, help="lowest frequency, Hz [0.5]")
    t.add_argument("--fmax", type=_number, default=20.0, help="highest frequency, Hz [20]")
    t.add_argument("--n", type=_integer, default=40, help="number of frequencies [40]")
    t.add_argument("--log", action="store_true", help="log-spaced frequencies")
    t.add_argument("--nperseg", type=_integer, default=None, help="run: frame length [the "
                   "longest power of two giving >= 8 averages at 50 %% overlap]")
    t.add_argument("--png", default=None, help="also plot amplitude and phase (and, for a "
                   "run, coherence) to this PNG file")
    dg = sub.add_parser("diagnose", help="find the physics a model of the runs is missing")
    dg.add_argument("runs", nargs="+", help="RUN.toml (or .h5) files of one configuration")
    dg.add_argument("--with", dest="with_", default="",
                    help="effects already in the starting model, comma separated")
    dg.add_argument("--effects", default="", help="catalog subset to try [all]")
    dg.add_argument("--effects-from", action="append", default=[], metavar="FILE",
                    help=_EFFECTS_FROM)
    dg.add_argument("--max-rounds", type=_integer, default=4,
                    help="stop after this many rounds of adding an effect [4]")
    dg.add_argument("--json", default=None, help="write the diagnosis JSON here")
    dg.add_argument("--rerun", default=None, help="write a Rerun recording (.rrd)")
    dg.add_argument("--report", default=None, help="write an HTML report")
    cp = sub.add_parser("compare", help="how a model with given effects fits the runs")
    cp.add_argument("runs", nargs="+")
    cp.add_argument("--with", dest="with_", default="",
                    help="effects in the model, comma separated")
    cp.add_argument("--effects-from", action="append", default=[], metavar="FILE",
                    help=_EFFECTS_FROM)
    cp.add_argument("--json", action="store_true")
    ident = sub.add_parser("identify", help="identify the report's parameters from runs")
    ident.add_argument("runs", nargs="+", help="RUN.toml (or .h5) files of one configuration")
    ident.add_argument("--json", nargs="?", const="-", default=None,
                       help="write JSON (to a file, or stdout with no value)")
    asx = sub.add_parser("assess", help="how the table changes what a specimen feels: the "
                         "five models of §9.4, coupled modes, spectra, a verdict and plots")
    asx.add_argument("specimen", nargs="?", default="sdof_frame",
                     help="a specimen preset (sdof_frame, table8_1, ...) or a TOML file with "
                          "a [specimen] table (sdof or shear_building) [sdof_frame]")
    asx.add_argument("--record", default="elcentro",
                     help="elcentro, a .AT2 or .csv file, or fema:ID[a|b] [elcentro]")
    asx.add_argument("--raw", action="store_true",
                     help="use the record as recorded, without the §9.2 processing "
                          "(length scale 3.2801, 4 in peak command)")
    asx.add_argument("--out", default="vtable-assess", help="folder for the plots "
                     "[vtable-assess]")
    asx.add_argument("--json", action="store_true")
    sd = sub.add_parser("study", help="a heights x records study on Dask, stored as it "
                        "runs and resumable")
    sd.add_argument("--store", required=True, help="results folder (resumed if it exists)")
    sd.add_argument("--heights", type=_number, nargs="+", required=True,
                    help="specimen heights above the actuator line, in")
    sd.add_argument("--records", nargs="+", default=["elcentro"],
                    help="elcentro, .AT2/.csv files, fema:ID [elcentro]")
    sd.add_argument("--specimen", default="sdof_frame", help="SDOF specimen [sdof_frame]")
    sd.add_argument("--model", choices=["virtual", "analytic"], default="virtual",
                    help="the virtual table (MuJoCo) or the analytical models [virtual]")
    sd.add_argument("--duration", type=_number, default=None,
                    help="seconds of each processed record (virtual: 4 by default)")
    sd.add_argument("--scheduler", default=None, help="a Dask scheduler address "
                    "[a local cluster]")
    sd.add_argument("--workers", type=_integer, default=2, help="local cluster workers [2]")
    sd.add_argument("--json", action="store_true")
    pr = sub.add_parser("presets", help="list the named configurations")
    pr.add_argument("--json", action="store_true")
    return p


# ---- commands ---------------------------------------------------------------------------
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


def _print_modes(d: dict[str, Any]) -> None:
    print(f"{d['model']}: {'stable' if d['stable'] else 'UNSTABLE'}")
    print(f"  {'mode':>4}  {'f (Hz)':>9}  {'damping':>8}")
    for i, m in enumerate(d["modes"], 1):
        print(f"  {i:>4}  {m['f_hz']:9.4f}  {m['damping']:8.4f}")
    if d["real_roots_per_s"]:
        print("  real roots (1/s): " + ", ".join(f"{r:.2f}" for r in d["real_roots_per_s"]))


def _print_margins(d: dict[str, Any]) -> None:
    print(f"{d['model']}: {d['loop']}")
    print(f"  gain margin  {d['gain_margin']:.3f}   at {d['f_phase_crossover_hz']:.3f} Hz")
    print(f"  phase margin {d['phase_margin_deg']:.2f} deg at {d['f_gain_crossover_hz']:.3f} Hz")


def cmd_modes(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.analytic import configs

    model = configs.load(a.config)
    model.check_stable()
    return _modes_dict(model)


def cmd_margins(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.analytic import configs

    return _margins_dict(configs.load(a.config), a.out, a.inp)


def _is_run(path: str) -> bool:
    from pathlib import Path

    from vtable.params.base import read_toml

    p = Path(path)
    if p.suffix in (".h5", ".hdf5"):
        return True
    if p.suffix != ".toml" or not p.is_file():
        return False
    return "format" in read_toml(p)  # a run file (model files have no format key)


def cmd_tf_run(a: argparse.Namespace) -> dict[str, Any]:
    """H1 with coherence between two channels of a run, on frames giving >= 8 averages
    (vtable.ident.frames) unless --nperseg says otherwise; too few averages are warned."""
    from vtable.ident import channels, transfer_function
    from vtable.ident.frames import FEWEST_AVERAGES, MIN_AVERAGES, averages, frame_for_averages
    from vtable.runs import read_any

    run = read_any(a.config)
    out = "avg_hdisp" if a.out == "x_t" else a.out
    inp = "h_span" if a.inp == "x_c" else a.inp
    x, y = run.channel(inp), run.channel(out)
    for name, kind in ((inp, "input"), (out, "output")):
        why = channels.channel_problem(run, name)
        if why:
            raise VtableError(f"{run.name}: {why}: no transfer function with it as the {kind}")
    if not (0 <= a.fmin < a.fmax):
        raise VtableError(f"need 0 <= --fmin < --fmax, got {a.fmin:g}, {a.fmax:g}")
    n_samples, warnings = len(x), []
    n8 = frame_for_averages(n_samples, MIN_AVERAGES)
    if a.nperseg is not None:
        if not 16 <= a.nperseg <= n_samples:
            raise VtableError(f"--nperseg must be between 16 and the run's {n_samples} samples, "
                              f"got {a.nperseg}")
        n, why = a.nperseg, "given --nperseg"
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
    tf = transfer_function(x, y, run.fs, n)
    sel = (tf.f >= a.fmin) & (tf.f <= a.fmax)
    d = {"model": run.name, "output": out, "input": inp, "f_hz": tf.f[sel].tolist(),
         "magnitude": np.abs(tf.H[sel]).tolist(),
         "phase_deg": np.degrees(np.angle(tf.H[sel])).tolist(),
         "coherence": tf.coherence[sel].tolist(), "averages": tf.averages, "nperseg": n,
         "resolution_hz": run.fs / n, "frame": why, "coherence_meaningful": nd > 1,
         "warnings": warnings, "notes": list(run.reports)}
    if a.png:
        from vtable.viz.figures import transfer_function_png

        transfer_function_png(a.png, tf.f[sel], tf.H[sel], tf.coherence[sel] if nd > 1 else None,
                              f"{run.name}: {out}/{inp} ({nd} averages)")
        d["png"] = a.png
    return d


def cmd_tf(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.analytic import configs

    if _is_run(a.config):
        return cmd_tf_run(a)

    if not (0 < a.fmin < a.fmax):
        raise VtableError(f"need 0 < --fmin < --fmax, got {a.fmin:g}, {a.fmax:g}")
    if a.n < 2:
        raise VtableError(f"--n must be at least 2, got {a.n}")
    model = configs.load(a.config)
    model.check_stable()
    f = (np.geomspace if a.log else np.linspace)(a.fmin, a.fmax, a.n)
    H = model.freqresp(f, a.out, a.inp)
    d = {"model": model.title, "output": a.out, "input": a.inp, "f_hz": f.tolist(),
         "magnitude": np.abs(H).tolist(), "phase_deg": np.degrees(np.angle(H)).tolist()}
    if a.png:
        from vtable.viz.figures import transfer_function_png

        transfer_function_png(a.png, f, H, None, f"{model.title}: {a.out}/{a.inp}")
        d["png"] = a.png
    return d


def _print_tf(d: dict[str, Any]) -> None:
    run = "coherence" in d
    print(f"{d['model']}: {d['output']}/{d['input']}"
          + (f" (H1, {d['averages']} average{'s' * (d['averages'] != 1)} of "
             f"{d['nperseg']}-point frames, Δf "
             f"{d['resolution_hz']:.3g} Hz: {d['frame']})" if run else ""))
    for n in d.get("notes", []):
        print(f"  note: {n}")
    for w in d.get("warnings", []):
        print(f"  ⚠ {w}")
    coh = d.get("coherence")
    show = run and d.get("coherence_meaningful", True)
    print(f"  {'f (Hz)':>9}  {'|H|':>10}  {'phase (deg)':>11}" + ("  coherence" if run else ""))
    for i, (f, m, p) in enumerate(zip(d["f_hz"], d["magnitude"], d["phase_deg"], strict=True)):
        print(f"  {f:9.3f}  {m:10.4g}  {p:11.2f}"
              + ((f"  {coh[i]:9.3f}" if show else f"  {'—':>9}") if run else ""))
    if d.get("png"):
        print(f"  wrote {d['png']}")


def _load_effects(a: argparse.Namespace) -> list[str]:
    """Register the effects of the user's files (--effects-from); their names."""
    from vtable.effects import load_file

    return [n for f in getattr(a, "effects_from", []) for n in load_file(f)]


def _effects_list(text: str) -> list[str]:
    from vtable.effects.registry import get as effect

    names = [e.strip() for e in text.split(",") if e.strip()]
    for e in names:
        effect(e)
    return names


class _Progress:
    """A live progress bar on stderr (plain lines when it is not a terminal)."""

    def __init__(self) -> None:
        self.tty = sys.stderr.isatty()
        self.last = ""

    def __call__(self, i: int, n: int, label: str) -> None:
        width = 28
        done = int(width * i / max(n, 1))
        line = f"[{'#' * done}{'-' * (width - done)}] {i}/{n} {label}"
        if self.tty:
            print("\r" + line.ljust(80), end="", file=sys.stderr, flush=True)
            if i >= n:
                print(file=sys.stderr)
        elif label != self.last:
            print(line, file=sys.stderr, flush=True)
        self.last = label


def cmd_diagnose(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.diagnose.engine import Diagnoser, DiagnosisInterrupted, localise
    from vtable.fileio import write_text
    from vtable.runs import campaign

    _load_effects(a)
    runs = campaign(a.runs)
    if a.max_rounds < 1:
        raise VtableError(f"--max-rounds must be at least 1, got {a.max_rounds}")
    diag = Diagnoser(runs, _effects_list(a.with_), catalog=_effects_list(a.effects) or None,
                     progress=_Progress(), max_rounds=a.max_rounds)
    try:
        d = diag.diagnose()
    except DiagnosisInterrupted as e:
        # Ctrl-C: keep the rounds that finished, one line, exit code 130 (main)
        part = e.partial.to_json()
        part["localisation"] = localise(e.partial)
        wrote = "nothing written (no --json)"
        if a.json:
            write_text(a.json, json.dumps(jsonable(part), indent=2))
            wrote = f"wrote {a.json}"
        print(("\n" if sys.stderr.isatty() else "")
              + f"vtable: interrupted after round {len(e.partial.rounds)}; {wrote}",
              file=sys.stderr)
        e.reported = True  # main() exits 130 without a second line
        raise
    out = d.to_json()
    out["localisation"] = localise(d)
    if a.json:
        write_text(a.json, json.dumps(jsonable(out), indent=2))
        out["_wrote"] = [a.json]
    if a.rerun:
        from vtable.viz.diagnosis_rerun import log_diagnosis

        log_diagnosis(d, a.rerun)
        out.setdefault("_wrote", []).append(a.rerun)
    if a.report:
        from vtable.viz.diagnosis_report import write_report

        write_report(d, a.report)
        out.setdefault("_wrote", []).append(a.report)
    return out


def _print_diagnose(d: dict[str, Any]) -> None:
    for i, n in enumerate(d.get("notes", [])):
        print(("notes:\n" if i == 0 else "") + f"  {n}")
    print("starting model: servo loop + specimen"
          + (f" + {', '.join(d['start_effects'])}" if d["start_effects"] else ""))
    print(f"  held-out error {d['start_error']:.2%} (noise floor {d['noise_floor']:.2%})")
    print(f"  where: {d['localisation']}")
    for i, r in enumerate(d["rounds"], 1):
        print(f"\nround {i}: " + (f"added {r['added']}" if r["added"] else "nothing added"))
        print(f"  {'rank':>4}  {'effect':<28} {'held-out':>9}  evidence")
        for k, c in enumerate(r["ranking"], 1):
            print(f"  {k:>4}  {c['effect']:<28} {c['error_after']:9.2%}  "
                  + (c["evidence"] if k <= 3 else ""))
            if c.get("flags"):
                print(f"  {'':>4}  {'':<28} {'':>9}  fit at a bound: " + "; ".join(c["flags"]))
    print("\nerror history: " + " -> ".join(
        [f"{d['start_error']:.2%}"] + [f"{r['error']:.2%} (+{r['added']})"
                                        for r in d["rounds"] if r["added"]]))
    base = d.get("base", {})
    if base:
        print("base: " + "; ".join(f"{k} {v['fitted']:.4g} (declared {v['declared']:.4g}, "
                                   f"bounds {v['bounds'][0]:g}-{v['bounds'][1]:g})"
                                   for k, v in base.items()))
    u = d.get("unexplained")
    print("unexplained: " + ("none (the final error is consistent with the noise floor)"
                             if u is None else f"{u['ratio_to_floor']:.1f} x the noise floor, "
                                               f"{u['where']}"))
    print(f"verdict: {d['verdict']}")
    for f in d.get("_wrote", []):
        print(f"wrote {f}")


def cmd_compare(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.diagnose.compare import UNEXPLAINED_RULE, localisation_text, unexplained
    from vtable.diagnose.model import TableModel
    from vtable.runs import campaign

    _load_effects(a)
    runs = campaign(a.runs)
    m = TableModel(_effects_list(a.with_)).fit(runs)
    c = m.comparison()
    ol = m.physics_.open_loop
    return {"effects": list(m.effects), "params": m.physics_.effects,
            "base": {"f_o_hz": ol.f_o, "xi_o": ol.xi_o, "k_o_per_s": ol.k_o},
            "base_fit": m.base_, "flags": m.flags_,
            "error": c.error, "noise_floor": c.noise_floor, "per_run": c.per_run,
            "bands": c.bands, "localisation": localisation_text(c),
            "unexplained": unexplained(c), "unexplained_rule": UNEXPLAINED_RULE,
            "notes": m.notes_}


def _print_compare(d: dict[str, Any]) -> None:
    for i, n in enumerate(d.get("notes", [])):
        print(("notes:\n" if i == 0 else "") + f"  {n}")
    print("model: servo loop + specimen" + (f" + {', '.join(d['effects'])}" if d["effects"]
                                           else ""))
    b = d["base"]
    print(f"  base loop: f_o {b['f_o_hz']:.2f} Hz, ξ_o {b['xi_o']:.3f}, k_o {b['k_o_per_s']:.2f}")
    for e, p in d["params"].items():
        print(f"  {e}: " + ", ".join(f"{k} = {v:.4g}" for k, v in p.items()))
    for f in d.get("flags", []):
        print(f"  fit at a bound: {f}")
    print(f"  held-out error {d['error']:.2%}, noise floor {d['noise_floor']:.2%}")
    for run, errs in d["per_run"].items():
        print(f"  {run}: " + ", ".join(f"{g} {e:.1%}" for g, e in errs.items()))
    print(f"  where: {d['localisation']}")
    u = d.get("unexplained")
    print("  unexplained: " + ("none (the error is consistent with the noise floor)"
                               if u is None else f"{u['ratio_to_floor']:.1f} x the noise floor, "
                                                 f"{u['where']}"))


def cmd_identify(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.ident.report import identify_run
    from vtable.runs import campaign

    runs = campaign(a.runs)
    return {"format": "vtable-identification/1", "runs": [identify_run(r) for r in runs]}


def _print_identify(d: dict[str, Any]) -> None:
    from vtable.ident.report import print_identification

    for r in d["runs"]:
        print_identification(r)


def cmd_demo(a: argparse.Namespace) -> dict[str, Any]:
    out = _demo_analytic()
    if not a.no_sim:
        out["simulation"] = _demo_simulation(a.out)
    return out


def cmd_simulate(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.effects.registry import parse_spec
    from vtable.sim.experiment import load_specimen, make_command, run_experiment

    _load_effects(a)
    effects = dict(parse_spec(e) for e in a.effect)
    spec = load_specimen(a.specimen)
    cmd = make_command(a.kind, duration=a.duration, band=tuple(a.band), peak_in=a.peak,
                       frequency=a.freq, seed=a.seed, record=a.record)
    exp = run_experiment(spec, cmd, valve=a.valve, out=a.out, rerun=a.rerun,
                         exaggeration=a.exaggerate, effects=effects)
    summary = _sim_summary(exp)
    summary.update({"command": cmd.name, "specimen": spec.title,
                    "duration_s": float(exp.result.t[-1] - exp.result.t[0])})
    return summary


def _print_simulate(s: dict[str, Any]) -> None:
    print(f"{s['specimen']}: {s['command']}, {s['duration_s']:.2f} s")
    for n in s["notes"]:
        print(f"  note: {n}")
    print(f"  {'channel':<12} {'peak':>10}")
    for k, v in s["peaks"].items():
        print(f"  {k:<12} {v['peak']:10.4g} {v['unit']}")
    for e in s["exceedances"]:
        print(f"  limit: {e}")
    if s["files"]:
        print("  wrote " + ", ".join(s["files"]))


def cmd_export(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.mjcf.export import export_mjcf
    from vtable.sim.experiment import load_specimen

    files = export_mjcf(load_specimen(a.specimen), a.out)
    return {"files": [str(f) for f in files]}


def _demo_analytic() -> dict[str, Any]:
    from vtable.analytic import configs

    model = configs.load(configs.DEFAULT)
    model.check_stable()
    f = np.linspace(0.2, 15.0, 2961)
    xt, xe = np.abs(model.freqresp(f, "x_t", "x_c")), np.abs(model.freqresp(f, "x_eff", "x_c"))
    th = np.abs(model.freqresp(f, "theta_h", "x_c"))
    near = f < 5.0
    return {"configuration": configs.DEFAULT, **_modes_dict(model),
            "margins": _margins_dict(model, "x_t", "x_c"),
            "x_t/x_c": {"peak": float(xt[near].max()),
                        "f_peak_hz": float(f[near][xt[near].argmax()]),
                        "notch": float(xt[near].min()),
                        "f_notch_hz": float(f[near][xt[near].argmin()])},
            "x_eff/x_c notch_hz": float(f[near][xe[near].argmin()]),
            "theta_h/x_c peak_hz": float(f[near][th[near].argmax()])}


def _sim_summary(exp) -> dict[str, Any]:
    """Peak table of a virtual-table experiment (report units)."""
    ch = {k: exp.channel(k) for k in exp.run.channels}
    keys = [("h_span", "in"), ("avg_hdisp", "in"), ("pitch_disp", "rad"), ("pitch_acc", "rad/s2"),
            ("acc_n_ne", "g"), ("pot_n_sw", "in"), ("h1_force", "kip"), ("v1_force", "kip"),
            ("p1_stab", "kip")]
    peaks = {k: {"peak": float(np.max(np.abs(ch[k]))), "unit": u} for k, u in keys if k in ch}
    return {"peaks": peaks, "exceedances": [str(e) for e in exp.result.exceedances],
            "files": [str(f) for f in exp.files], "notes": list(exp.notes)}


def _demo_simulation(out: str) -> dict[str, Any]:
    from vtable.sim.experiment import load_specimen, make_command, run_experiment
    from vtable.studies import response_spectrum
    from vtable.units import to_si

    spec = load_specimen("sdof_frame")
    cmd = make_command("earthquake")
    exp = run_experiment(spec, cmd, out=f"{out}/sdof_elcentro", rerun=f"{out}/sdof_elcentro.rrd")
    res = exp.result
    h = exp.result.built.structure_heights[-1]
    x_t, th = res.joint("x"), res.joint("pitch")
    x_s = res.joint("x_s")
    dt = res.t[1] - res.t[0]
    a_eff = res.joint("x", "qacc") + h * res.joint("pitch", "qacc")
    a_cmd = res.command_acc
    T_s = 1 / spec.frequency
    periods = np.array([T_s])
    ratio = float(response_spectrum(a_eff, dt, periods, 0.05).psa[0]
                  / response_spectrum(a_cmd, dt, periods, 0.05).psa[0])
    summary = _sim_summary(exp)
    summary.update({
        "command": cmd.name, "duration_s": float(res.t[-1] - res.t[0]),
        "peak_x_t_in": float(np.max(np.abs(x_t)) / to_si(1, "in")),
        "peak_theta_h_in": float(np.max(np.abs(th * h)) / to_si(1, "in")),
        "peak_x_s_in": float(np.max(np.abs(x_s)) / to_si(1, "in")),
        "effective_spectrum_ratio": ratio, "spectrum_period_s": T_s})
    return summary


def _print_demo(d: dict[str, Any]) -> None:
    print("vtable demo: the SDOF braced frame (68 kips, 219 in) on the EERC table")
    print("hybrid model, report Table 9.1 (horizontal servo loop + rocking spring/dashpot)\n")
    _print_modes(d)
    print()
    _print_margins(d["margins"])
    p = d["x_t/x_c"]
    print(f"\ntable motion x_t/x_c: peak {p['peak']:.2f} at {p['f_peak_hz']:.2f} Hz, "
          f"notch {p['notch']:.2f} at {p['f_notch_hz']:.2f} Hz")
    print(f"effective motion (x_t + θh)/x_c: notch at {d['x_eff/x_c notch_hz']:.2f} Hz "
          f"(fixed-base 2.87 Hz); pitch θh/x_c peaks at {d['theta_h/x_c peak_hz']:.2f} Hz")
    if "simulation" in d:
        _print_simulation(d["simulation"])


def _print_simulation(s: dict[str, Any]) -> None:
    print(f"\nvirtual table (MuJoCo + servo controllers): {s['command']}, "
          f"{s['duration_s']:.1f} s, §9.2 processing (length 3.2801, time 1.811, 4 in)")
    print(f"  {'channel':<12} {'peak':>10}")
    for k, v in s["peaks"].items():
        print(f"  {k:<12} {v['peak']:10.4g} {v['unit']}")
    print(f"  table x_t {s['peak_x_t_in']:.3f} in, pitch θh {s['peak_theta_h_in']:.3f} in, "
          f"structure x_s {s['peak_x_s_in']:.3f} in")
    print(f"  effective-motion spectrum ratio PSA(x_t + hθ)/PSA(command) at the fixed-base "
          f"period {s['spectrum_period_s']:.3f} s, 5 %: {s['effective_spectrum_ratio']:.3f}")
    for e in s["exceedances"]:
        print(f"  limit: {e}")
    if s["files"]:
        print("  wrote " + ", ".join(s["files"]))


def cmd_assess(a: argparse.Namespace) -> dict[str, Any]:
    from dataclasses import replace
    from pathlib import Path

    import numpy as np

    from vtable.signals.processing import process_record
    from vtable.signals.records import load_record
    from vtable.sim.experiment import load_specimen
    from vtable.studies import interaction as ia
    from vtable.viz import figures

    rec = load_record(a.record)
    if a.raw:
        acc, dt, label = rec.acc, rec.dt, rec.name
    else:
        cmd = process_record(rec)
        acc, dt, label = cmd.acceleration, cmd.dt, f"{rec.name} (§9.2 processed)"
    res = ia.assess(load_specimen(a.specimen), acc, dt, label)
    s = res.specimen
    out = Path(a.out)
    f_s = np.linspace(0.5, 10.0, 39)
    ref = np.column_stack([f_s, np.full_like(f_s, s.damping)])
    xi = np.linspace(0.0, 0.20, 21)
    files = [
        figures.psv_spectra_png(out / "psv_spectra.png", res.periods, res.psv,
                                f"{s.title}: PSV, {label}, ξ_s {100 * s.damping:.0f} %"),
        figures.coupled_sweep_png(out / "coupled_vs_frequency.png", f_s, "f_s (Hz)",
                                  ia.sweep(s, "frequency", f_s), ref,
                                  "coupled mode vs structural frequency (Figs 9.4-9.5)"),
        figures.coupled_sweep_png(out / "coupled_vs_damping.png", 100 * xi, "ξ_s (%)",
                                  ia.sweep(s, "damping", xi, names=["hybrid"]),
                                  np.column_stack([np.full_like(xi, s.frequency), xi]),
                                  "coupled mode vs structural damping (Figs 9.7-9.8)"),
    ]
    for par, label_x in (("weight", "mass"), ("height", "height")):
        curves = {f"{label_x} x{k:g}": ia.sweep(replace(s, **{par: getattr(s, par) * k}),
                                                "frequency", f_s, names=["hybrid"])["hybrid"]
                  for k in (0.5, 1.0, 1.5)}
        files.append(figures.coupled_sweep_png(
            out / f"coupled_vs_{label_x}.png", f_s, "f_s (Hz)", curves, ref,
            f"hybrid model: varying structural {label_x} (Figs 9.9-9.12)"))
    return {"verdict": res.verdict(), "specimen": s.title, "record": label,
            "modes": {k: {"f_hz": f, "damping": z} for k, (f, z) in res.modes.items()},
            "psv_at_specimen_period_m_s": res.psv_at_specimen,
            "rocking_share": res.rocking_share, "time_elongation": res.elongation,
            "compensated_error": res.compensated_error, "files": [str(f) for f in files],
            "notes": list(getattr(rec, "notes", ()))}


def _print_assess(d: dict[str, Any]) -> None:
    for n in d["notes"]:
        print(f"note: {n}")
    print(d["verdict"])
    print("wrote " + ", ".join(d["files"]))


def cmd_study(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.studies.scaleout import height_record_study, run_study

    common: dict[str, Any] = {"specimen": a.specimen}
    if a.duration is not None or a.model == "virtual":
        common["duration"] = a.duration if a.duration is not None else 4.0
    study = height_record_study(a.heights, a.records, a.model, **common)
    return {"store": a.store, "model": a.model,
            "points": run_study(study, a.store, scheduler=a.scheduler, n_workers=a.workers)}


def _print_study(d: dict[str, Any]) -> None:
    print(f"{len(d['points'])} points in {d['store']} ({d['model']})")
    for k, r in d["points"].items():
        if d["model"] == "virtual":
            ratio = " ".join(f"{x:.2f}" for x in r["psa_ratio"])
            print(f"  {k:14s} h {r['height_in']:6.0f} in  peak θ "
                  f"{1e3 * r['peaks_si']['pitch_disp']:.3f} mrad  PSA(x_t+hθ)/PSA(x_c) "
                  f"at {r['periods_s']} s: {ratio}")
        else:
            f, xi = r["modes"]["hybrid"]
            ps = r["psv_at_specimen"]
            dv = 100 * (ps["hybrid"] / ps["fixed base"] - 1)
            print(f"  {k:14s} h {r['height_in']:6.0f} in  hybrid f_c {f:.2f} Hz, ξ_c "
                  f"{100 * xi:.1f} %, PSV vs fixed {dv:+.0f} %")


def cmd_presets(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.analytic import configs

    return {"configurations": configs.names()}


_COMMANDS = {
    "demo": (cmd_demo, _print_demo),
    "modes": (cmd_modes, _print_modes),
    "margins": (cmd_margins, _print_margins),
    "tf": (cmd_tf, _print_tf),
    "presets": (cmd_presets, lambda d: print("\n".join(d["configurations"]))),
    "simulate": (cmd_simulate, _print_simulate),
    "export-mjcf": (cmd_export, lambda d: print("wrote " + ", ".join(d["files"]))),
    "identify": (cmd_identify, _print_identify),
    "diagnose": (cmd_diagnose, _print_diagnose),
    "compare": (cmd_compare, _print_compare),
    "assess": (cmd_assess, _print_assess),
    "study": (cmd_study, _print_study),
}


def _interrupted(e: BaseException) -> bool:
    """A KeyboardInterrupt, or an error raised because one was pending (numba-compiled code
    returns a SystemError chained to the interrupt)."""
    seen = set()
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False


def _quiet_stdout() -> None:
    """After a closed pipe: send what is left of stdout to /dev/null, so the interpreter's
    final flush does not complain."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


def _emit(a: argparse.Namespace, result: dict[str, Any], show) -> None:
    if a.command == "diagnose":
        show(result)
    elif a.command == "identify" and a.json not in (None, "-"):
        from vtable.fileio import write_text

        write_text(a.json, json.dumps(jsonable(result), indent=2))
        show(result)
        print(f"wrote {a.json}")
    elif a.json:
        print(json.dumps(jsonable(result), indent=2))
    else:
        show(result)
    sys.stdout.flush()


def main(argv: list[str] | None = None) -> int:
    """Run one command; exit codes: 0 ok, 2 bad input (one line on stderr), 3 unstable
    configuration, 130 interrupted (Ctrl-C), 141 output pipe closed (quietly)."""
    try:
        a = _parser().parse_args(argv)
        run, show = _COMMANDS[a.command]
        _emit(a, run(a), show)
        return 0
    except UnstableError as e:
        print(f"vtable: {e}", file=sys.stderr)
        return 3
    except VtableError as e:
        print(f"vtable: error: {e}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        _quiet_stdout()
        return 141
    except KeyboardInterrupt as e:
        if not getattr(e, "reported", False):
            print("vtable: interrupted", file=sys.stderr)
        return 130
    except Exception as e:
        if _interrupted(e):
            print("vtable: interrupted", file=sys.stderr)
            return 130
        raise


if __name__ == "__main__":
    sys.exit(main())
