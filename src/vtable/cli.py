"""The ``vtable`` command line: demo, modes, tf, margins, presets."""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from typing import Any

from vtable import __version__, verbs
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


_JSON_HELP = ("the result as JSON: on stdout, or with FILE written there (the table is "
              "printed); the same for every command")
def _add_json(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", nargs="?", const="-", default=None, metavar="FILE", help=_JSON_HELP)


_CALIBRATE = ("how far the base may move from the runs' declarations: 'none', or "
              "NAME=VALUE,... of frequency (relative, 0.05), damping (factor, 3), mass "
              "(relative, 0.1), com_height (x declared, 2), pitch_inertia (factor, 1.5), "
              "prior_weight (0.3)")
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
        _add_json(c)
        return c

    d = sub.add_parser("demo", help="the built-in EERC configuration: coupled modes, margins, "
                       "and the SDOF frame on the virtual table under El Centro")
    _add_json(d)
    d.add_argument("--out", default="vtable-demo", help="folder for the run and the .rrd "
                   "[vtable-demo]")
    d.add_argument("--no-sim", action="store_true", help="analytical part only")
    sim = sub.add_parser("simulate", help="run a command on the multibody virtual table")
    sim.add_argument("--specimen", default="sdof_frame",
                     help="none, concrete_blocks, sdof_frame, table5_1, table8_1 or a TOML "
                          "file with a [specimen] table [sdof_frame]")
    sim.add_argument("--table", default="eerc",
                     help="the table: a preset (eerc, lnec-st1d) or a TOML file with a [table] "
                          "in the run format's keys [eerc]")
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
                     help="linear servovalves (eqs 6.1-6.5) or appendix C valves on H1-H3; "
                          "nonlinear is an alias for --effect valve_flow_nonlinearity "
                          "--effect flow_saturation (at their defaults unless given)")
    sim.add_argument("--effect", action="append", default=[], metavar="NAME[:P=V,...]",
                     help="add an effect to the standard table, with parameters in its units "
                          "(e.g. actuator_friction:friction=3); repeatable")
    sim.add_argument("--effects-from", action="append", default=[], metavar="FILE",
                     help=_EFFECTS_FROM)
    sim.add_argument("--out", default=None, help="run file stem (writes STEM.csv, STEM.toml)")
    sim.add_argument("--rerun", default=None, help="write a Rerun recording (.rrd)")
    sim.add_argument("--exaggerate", type=_number, default=50.0,
                     help="pitch/roll exaggeration in the 3D view [50]")
    _add_json(sim)
    ex = sub.add_parser("export-mjcf", help="write the virtual table as MJCF + meshes")
    ex.add_argument("--specimen", default="none")
    ex.add_argument("--out", required=True, help="folder")
    _add_json(ex)
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
    dg.add_argument("--calibrate", default="", metavar="SPEC", help=_CALIBRATE)
    _add_json(dg)
    dg.add_argument("--rerun", default=None, help="write a Rerun recording (.rrd)")
    dg.add_argument("--report", default=None, help="write an HTML report")
    cp = sub.add_parser("compare", help="how a model with given effects fits the runs")
    cp.add_argument("runs", nargs="+")
    cp.add_argument("--with", dest="with_", default="",
                    help="effects in the model, comma separated")
    cp.add_argument("--calibrate", default="", metavar="SPEC", help=_CALIBRATE)
    cp.add_argument("--effects-from", action="append", default=[], metavar="FILE",
                    help=_EFFECTS_FROM)
    _add_json(cp)
    ident = sub.add_parser("identify", help="identify the report's parameters from runs")
    ident.add_argument("runs", nargs="+", help="RUN.toml (or .h5) files of one configuration")
    _add_json(ident)
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
    _add_json(asx)
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
    _add_json(sd)
    pr = sub.add_parser("presets", help="list the named configurations")
    _add_json(pr)
    return p


# ---- commands ---------------------------------------------------------------------------
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
                print(f"  {'':>4}  {'':<28} {'':>9}  flags: " + "; ".join(c["flags"]))
    print("\nerror history: " + " -> ".join(
        [f"{d['start_error']:.2%}"] + [f"{r['error']:.2%} (+{r['added']})"
                                        for r in d["rounds"] if r["added"]]))
    _print_base(d.get("base", {}))
    u = d.get("unexplained")
    print("unexplained: " + ("none (the final error is consistent with the noise floor)"
                             if u is None else f"{u['ratio_to_floor']:.1f} x the noise floor, "
                                               f"{u['where']}"))
    print(f"verdict: {d['verdict']}")
    for f in d.get("_wrote", []):
        print(f"wrote {f}")


def _print_base(base: dict[str, Any], indent: str = "") -> None:
    """The calibrated base: declared -> fitted within its bounds, one line each."""
    if not base:
        return
    print(f"{indent}base (declared -> fitted, bounds):")
    for k, v in base.items():
        u = "" if v["unit"] == "1" else f" {v['unit']}"
        lo, hi = v["bounds"]
        moved = (v["fitted"] / v["declared"] - 1) if v["declared"] else float("nan")
        print(f"{indent}  {k:<28} {v['declared']:.4g} -> {v['fitted']:.4g}{u} ({moved:+.1%}; "
              f"bounds {lo:.4g}-{hi:.4g})")


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
        print(f"  flag: {f}")
    _print_base(d.get("base_fit", {}), indent="  ")
    print(f"  held-out error {d['error']:.2%}, noise floor {d['noise_floor']:.2%}")
    for run, errs in d["per_run"].items():
        print(f"  {run}: " + ", ".join(f"{g} {e:.1%}" for g, e in errs.items()))
    print(f"  where: {d['localisation']}")
    u = d.get("unexplained")
    print("  unexplained: " + ("none (the error is consistent with the noise floor)"
                               if u is None else f"{u['ratio_to_floor']:.1f} x the noise floor, "
                                                 f"{u['where']}"))


def _print_identify(d: dict[str, Any]) -> None:
    from vtable.ident.result import Identification

    for r in d["runs"]:
        print(Identification.from_json(r).report())


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


def _print_assess(d: dict[str, Any]) -> None:
    for n in d["notes"]:
        print(f"note: {n}")
    print(d["verdict"])
    print("wrote " + ", ".join(d["files"]))


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


# ---- commands: parse, call one library function (vtable.verbs), format ----------------
def cmd_modes(a: argparse.Namespace) -> dict[str, Any]:
    return verbs.modes(a.config)


def cmd_margins(a: argparse.Namespace) -> dict[str, Any]:
    return verbs.margins(a.config, a.out, a.inp)


def cmd_tf(a: argparse.Namespace) -> dict[str, Any]:
    return verbs.tf(a.config, a.out, a.inp, a.fmin, a.fmax, a.n, a.log, a.nperseg, a.png)


def cmd_presets(a: argparse.Namespace) -> dict[str, Any]:
    return verbs.presets()


def cmd_identify(a: argparse.Namespace) -> dict[str, Any]:
    return verbs.identify(a.runs)


def cmd_compare(a: argparse.Namespace) -> dict[str, Any]:
    verbs.load_effects(a.effects_from)
    return verbs.compare(a.runs, verbs.effect_names(a.with_), a.calibrate)


def cmd_diagnose(a: argparse.Namespace) -> dict[str, Any]:
    from vtable.diagnose.engine import DiagnosisInterrupted

    verbs.load_effects(a.effects_from)
    json_path = None if a.json in (None, "-") else a.json
    try:
        out, _ = verbs.diagnose(a.runs, verbs.effect_names(a.with_),
                                verbs.effect_names(a.effects), a.max_rounds, _Progress(),
                                json_path, a.rerun, a.report, a.calibrate)
    except DiagnosisInterrupted as e:
        # Ctrl-C: the rounds finished are in the JSON; one line; exit code 130 (main)
        wrote = f"wrote {e.wrote}" if getattr(e, "wrote", None) else "nothing written (no --json)"
        print(("\n" if sys.stderr.isatty() else "")
              + f"vtable: interrupted after round {len(e.partial.rounds)}; {wrote}",
              file=sys.stderr)
        e.reported = True
        raise
    if json_path:
        out["_json_written"] = True  # _emit prints the table, not the JSON
    return out


def cmd_simulate(a: argparse.Namespace) -> dict[str, Any]:
    verbs.load_effects(a.effects_from)
    return verbs.simulate(a.specimen, a.kind, duration=a.duration, band=tuple(a.band),
                          peak=a.peak, freq=a.freq, seed=a.seed, record=a.record,
                          valve=a.valve, effects=a.effect, out=a.out, rerun=a.rerun,
                          exaggerate=a.exaggerate, table=a.table)


def cmd_export(a: argparse.Namespace) -> dict[str, Any]:
    return verbs.export_mjcf(a.specimen, a.out)


def cmd_demo(a: argparse.Namespace) -> dict[str, Any]:
    return verbs.demo(a.out, not a.no_sim)


def cmd_assess(a: argparse.Namespace) -> dict[str, Any]:
    return verbs.assess(a.specimen, a.record, a.raw, a.out)


def cmd_study(a: argparse.Namespace) -> dict[str, Any]:
    return verbs.study(a.store, a.heights, a.records, a.specimen, a.model, a.duration,
                       a.scheduler, a.workers)


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
    """--json: JSON on stdout; --json FILE: JSON written there and the table printed;
    neither: the table."""
    if a.json == "-":
        print(json.dumps(jsonable({k: v for k, v in result.items() if not k.startswith("_")}),
                         indent=2))
    elif a.json:
        if not result.pop("_json_written", False):
            from vtable.fileio import write_text

            write_text(a.json, json.dumps(jsonable(result), indent=2))
            result.setdefault("_wrote", []).insert(0, a.json)
        show(result)
        if a.command not in ("diagnose",):
            for f in result.get("_wrote", []):
                print(f"wrote {f}")
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
