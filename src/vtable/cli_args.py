"""The ``vtable`` command line's arguments: one sub-parser per verb, numbers read strictly,
a bad argument one line (`VtableError`) rather than a usage dump."""

from __future__ import annotations

import argparse
import math
import re
from dataclasses import dataclass

from vtable import __version__, units
from vtable.errors import VtableError

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


@dataclass(frozen=True)
class Length:
    """A length a user typed: its value and unit ('2mm', '0.1 in'), or a bare number whose
    unit is the table's (`unit` None: inches on the report's tables, mm on a metric one)."""

    value: float
    unit: str | None = None

    def si(self, default_unit: str) -> float:
        """The length in metres, a bare number read in `default_unit`."""
        return units.to_si(self.value, self.unit or default_unit)


def _length(text: str) -> Length:
    """A positive plain number with an optional length unit of `vtable.units` (m, mm, cm,
    in, ft): '2mm', '0.1 in', '2'. A unit of another dimension ('0.3g', '2m/s2') or an
    unknown one is refused naming the length units."""
    m = re.fullmatch(r"\s*(" + _NUMBER.pattern + r")\s*(?P<unit>[A-Za-z%]\S*)?\s*", text,
                     re.ASCII)
    if not m:
        raise argparse.ArgumentTypeError(f"{text!r} is not a length (a number and a unit: "
                                          "2mm, 0.1in, 0.005m)")
    value, unit = _number(m.group(1)), m.group("unit")
    lengths = ", ".join(units.units_of("length"))
    if unit is not None and units.DIMENSIONS.get(unit) != "length":
        what = units.noun(units.DIMENSIONS.get(unit, "unknown"))
        what = ("an " if what[0] in "aeiu" else "a ") + what
        raise argparse.ArgumentTypeError(f"{text!r}: {unit!r} is {what} unit, not a length unit "
                                          f"(expected one of {lengths})")
    if not value > 0:
        raise argparse.ArgumentTypeError(f"{text!r}: a peak displacement must be > 0")
    return Length(value, unit)


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
_CONTROLLER_FROM = ("a Python file of your lab's controller kinds (it calls "
                    "vtable.controllers.kinds.register); a run's [table.controller] kind "
                    "may then name them")


def parser() -> argparse.ArgumentParser:
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
    sim.add_argument("--specimen", default=None,
                     help="none, concrete_blocks, sdof_frame, table5_1, table8_1 or a TOML "
                          "file with a [specimen] table [sdof_frame, or none when the "
                          "table's payload cannot carry it]")
    sim.add_argument("--table", default="eerc",
                     help="the table: a preset (eerc, lnec-st1d) or a TOML file with a [table] "
                          "in the run format's keys [eerc]")
    sim.add_argument("--command", default="random", dest="kind",
                     choices=["random", "sine", "pulse", "earthquake"])
    sim.add_argument("--record", default=None, help="earthquake: elcentro, a .AT2 or .csv "
                     "file, or fema:ID[a|b] [elcentro]")
    sim.add_argument("--duration", type=_number, default=None,
                     help="s [11; an earthquake: the whole processed record]")
    sim.add_argument("--band", type=_number, nargs=2, default=None,
                     help="Hz [0 25, cut to the table's band]")
    sim.add_argument("--peak", type=_length, default=None,
                     help="peak command displacement with its unit (2mm, 0.1in, 0.005m); a "
                          "bare number is in the table's unit (in on eerc, mm on a metric "
                          "table) [the command's default, scaled to 50 %% of the "
                          "table's stroke and 80 %% of its velocity and acceleration]")
    sim.add_argument("--freq", type=_number, default=2.0, help="sine frequency, Hz [2]")
    sim.add_argument("--seed", type=_integer, default=0)
    sim.add_argument("--noise", type=_number, default=0.0, metavar="FRACTION",
                     help="white Gaussian sensor noise on every measured channel, FRACTION x "
                          "its RMS (the command stays clean; seeded by --seed) [0]")
    sim.add_argument("--valve", choices=["linear", "nonlinear"], default="linear",
                     help="linear servovalves (eqs 6.1-6.5) or appendix C valves on H1-H3; "
                          "nonlinear is an alias for --effect valve_flow_nonlinearity "
                          "--effect flow_saturation (at their defaults unless given)")
    sim.add_argument("--effect", action="append", default=[], metavar="NAME[:P=V,...]",
                     help="add an effect to the standard table, with parameters in its units "
                          "(e.g. actuator_friction:friction=3); repeatable")
    sim.add_argument("--effects-from", action="append", default=[], metavar="FILE",
                     help=_EFFECTS_FROM)
    sim.add_argument("--controller-from", action="append", default=[], metavar="FILE",
                     help=_CONTROLLER_FROM)
    sim.add_argument("--out", default=None, help="run file stem (writes STEM.csv, STEM.toml)")
    sim.add_argument("--states", action="store_true",
                     help="also write the model's internal states (state_* columns, which "
                          "depend on the effects in it) [off: the run format's channels only]")
    sim.add_argument("--rerun", default=None, help="write a Rerun recording (.rrd)")
    sim.add_argument("--exaggerate", type=_number, default=50.0,
                     help="pitch/roll exaggeration in the 3D view [50]")
    _add_json(sim)
    ex = sub.add_parser("export-mjcf", help="write the virtual table as MJCF + meshes")
    ex.add_argument("--specimen", default="none",
                    help="a specimen preset or a TOML file with a [specimen] table [none]")
    ex.add_argument("--table", default="eerc",
                    help="the table: a preset (eerc, lnec-st1d) or a TOML file with a [table] "
                         "in the run format's keys [eerc]")
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
    dg.add_argument("--controller-from", action="append", default=[], metavar="FILE",
                    help=_CONTROLLER_FROM)
    dg.add_argument("--max-rounds", type=_integer, default=4,
                    help="stop after this many rounds of adding an effect [4]")
    dg.add_argument("--calibrate", default="", metavar="SPEC", help=_CALIBRATE)
    dg.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="a Dask scheduler's address (a lab's cluster, tcp://host:8786) to "
                         "fit the candidates on [a local cluster of this machine's cores]")
    _add_json(dg)
    dg.add_argument("--rerun", default=None, help="write a Rerun recording (.rrd)")
    dg.add_argument("--report", default=None, help="write an HTML report")
    dg.add_argument("--verbose", action="store_true",
                    help="print the verdict with its statistics too")
    cp = sub.add_parser("compare", help="how a model with given effects fits the runs")
    cp.add_argument("runs", nargs="+")
    cp.add_argument("--with", dest="with_", default="",
                    help="effects in the model, comma separated")
    cp.add_argument("--calibrate", default="", metavar="SPEC", help=_CALIBRATE)
    cp.add_argument("--effects-from", action="append", default=[], metavar="FILE",
                    help=_EFFECTS_FROM)
    cp.add_argument("--controller-from", action="append", default=[], metavar="FILE",
                    help=_CONTROLLER_FROM)
    _add_json(cp)
    cp.add_argument("--rerun", default=None, help="write a Rerun recording (.rrd)")
    cp.add_argument("--report", default=None, help="write an HTML report")
    dr = sub.add_parser("drive", help="the drive that makes the specimen feel a target "
                                      "motion, from a model calibrated on the runs (§10.2)")
    dr.add_argument("runs", nargs="+", help="RUN.toml (or .h5) files of one configuration")
    dr.add_argument("--target", required=True,
                    help="a CSV of time (s) and displacement, or a record as simulate "
                         "--record takes it (processed the same way)")
    dr.add_argument("--target-unit", default="in", help="the target CSV's displacement unit "
                                                        "[in]")
    dr.add_argument("--target-peak", type=_length, default=None,
                    help="scale the target to this peak displacement, with its unit (2in, "
                         "50mm); a bare number in --target-unit [a record: 4 in; a CSV: as "
                         "written]")
    dr.add_argument("--objective", default="effective", choices=["effective", "table"],
                    help="effective: x_t + θh at the specimen (§4.2.2); table: x_t "
                         "[effective]")
    dr.add_argument("--with", dest="with_", default="",
                    help="effects in the model, comma separated")
    dr.add_argument("--from", dest="from_", default=None, metavar="DIAG.json",
                    help="the model's effects from a diagnosis (vtable diagnose --json)")
    dr.add_argument("--calibrate", default="", metavar="SPEC", help=_CALIBRATE)
    dr.add_argument("--regularisation", type=_number, default=0.05,
                    help="λ of the regularised inverse, relative to max |H| [0.05]")
    dr.add_argument("--cap", type=_number, default=10.0,
                    help="the largest amplification of the target near the specimen's "
                         "fixed-base frequencies [10]")
    dr.add_argument("--band", type=_number, default=30.0, metavar="HZ",
                    help="the drive is corrected up to HZ; above, it is the target's [30]")
    dr.add_argument("--report", metavar="FILE.html",
                    help="an HTML report: settings, the table of figures, the figure")
    dr.add_argument("--update", action="append", default=[], metavar="RUN.toml",
                    help="a run measured with the previous drive: recalibrate with it and "
                         "correct the drive from its measured error; repeatable")
    dr.add_argument("--out", required=True, help="STEM: writes STEM.csv + STEM.toml")
    dr.add_argument("--format", dest="fmt", default="csv", choices=["csv", "txt"],
                    help="txt: also STEM.txt, two plain columns (time s, drive in) [csv]")
    dr.add_argument("--png", default=None, help="a figure: target, prediction, spectra")
    dr.add_argument("--effects-from", action="append", default=[], metavar="FILE",
                    help=_EFFECTS_FROM)
    _add_json(dr)
    ident = sub.add_parser("identify", help="identify the report's parameters from runs")
    ident.add_argument("runs", nargs="+", help="RUN.toml (or .h5) files of one configuration")
    ident.add_argument("--controller-from", action="append", default=[], metavar="FILE",
                       help=_CONTROLLER_FROM)
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
    wm = sub.add_parser("warm", help="the warm process that answers vtable diagnose in this "
                        "environment: whether one runs, its log; --stop ends it")
    wm.add_argument("--stop", action="store_true", help="end it (once its commands have)")
    _add_json(wm)
    return p

