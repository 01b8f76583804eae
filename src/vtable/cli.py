"""The ``vtable`` command line: parse the arguments (`vtable.cli_args`), call one library
function (`vtable.verbs`), format the typed result it returns: its `report()` on stdout,
or with ``--json`` its `to_json()` (on stdout, or written to FILE with the report printed;
the same for every verb). Asking `vtable.verbs` for a verb imports that verb's module
only, so a command loads what it uses and ``--help`` loads none."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable

from vtable import units, verbs
from vtable.cli_args import parser
from vtable.errors import UnstableError, VtableError, interrupted, sigint_seen
from vtable.fileio import write_text
from vtable.results import Result
from vtable.warm import WarmProcess


class _Progress:
    """A live progress bar on stderr (plain lines when it is not a terminal)."""

    def __init__(self) -> None:
        self.tty = sys.stderr.isatty()
        self.last = ""

    def __call__(self, i: int, n: int, label: str) -> None:
        if sigint_seen():  # an interrupt something swallowed: stop here
            raise KeyboardInterrupt
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



# ---- commands: parse, call one library function (vtable.verbs) ---------------------------
def cmd_modes(a: argparse.Namespace) -> Result:
    return verbs.modes(a.config)


def cmd_margins(a: argparse.Namespace) -> Result:
    return verbs.margins(a.config, a.out, a.inp)


def cmd_tf(a: argparse.Namespace) -> Result:
    return verbs.tf(a.config, a.out, a.inp, a.fmin, a.fmax, a.n, a.log, a.nperseg, a.png)


def cmd_presets(a: argparse.Namespace) -> Result:
    return verbs.presets()


def cmd_warm(a: argparse.Namespace) -> Result:
    return WarmProcess.of(a.stop)  # the command line's own (`vtable.warm`), not a library's


def cmd_identify(a: argparse.Namespace) -> Result:
    verbs.load_controllers(a.controller_from)
    return verbs.identify(a.runs)


def cmd_compare(a: argparse.Namespace) -> Result:
    verbs.load_controllers(a.controller_from)
    verbs.load_effects(a.effects_from)
    return verbs.compare(a.runs, verbs.effect_names(a.with_), a.calibrate, a.rerun, a.report)


def cmd_drive(a: argparse.Namespace) -> Result:
    verbs.load_effects(a.effects_from)
    return verbs.drive(a.runs, a.target, a.out, a.target_unit, a.objective,
                       verbs.effect_names(a.with_), a.from_, a.calibrate, a.regularisation,
                       a.cap, a.update, a.fmt, a.png,
                       None if a.target_peak is None else  # in --target-unit
                       units.from_si(a.target_peak.si(a.target_unit), a.target_unit),
                       band=a.band,
                       report=a.report)


def cmd_diagnose(a: argparse.Namespace) -> Result:
    diagnose, interrupted = verbs.diagnose, verbs.DiagnosisInterrupted  # loads the diagnosis
    verbs.load_controllers(a.controller_from)
    verbs.load_effects(a.effects_from)
    try:
        return diagnose(a.runs, verbs.effect_names(a.with_), verbs.effect_names(a.effects),
                        a.max_rounds, _Progress(), a.rerun, a.report, a.calibrate,
                        scheduler=a.scheduler)
    except interrupted as e:
        # Ctrl-C: the rounds finished are in the JSON; one line; exit code 130 (main)
        wrote = "nothing written (no --json)"
        if a.json not in (None, "-"):
            _write_json(a.json, e.partial)
            wrote = f"wrote {a.json}"
        print(("\n" if sys.stderr.isatty() else "")
              + f"vtable: interrupted after round {len(e.partial.rounds)}; {wrote}",
              file=sys.stderr)
        e.reported = True
        raise


def cmd_simulate(a: argparse.Namespace) -> Result:
    verbs.load_controllers(a.controller_from)
    verbs.load_effects(a.effects_from)
    band = tuple(a.band) if a.band else None
    return verbs.simulate(a.specimen, a.kind, duration=a.duration, band=band,
                          peak=a.peak, freq=a.freq, seed=a.seed, record=a.record,
                          valve=a.valve, effects=a.effect, out=a.out, rerun=a.rerun,
                          exaggerate=a.exaggerate, table=a.table, noise=a.noise,
                          states=a.states)


def cmd_export(a: argparse.Namespace) -> Result:
    return verbs.export_mjcf(a.specimen, a.out, a.table)


def cmd_demo(a: argparse.Namespace) -> Result:
    return verbs.demo(a.out, not a.no_sim)


def cmd_assess(a: argparse.Namespace) -> Result:
    return verbs.assess(a.specimen, a.record, a.raw, a.out)


def cmd_study(a: argparse.Namespace) -> Result:
    return verbs.study(a.store, a.heights, a.records, a.specimen, a.model, a.duration,
                       a.scheduler, a.workers)


_COMMANDS = {"demo": cmd_demo, "modes": cmd_modes, "margins": cmd_margins, "tf": cmd_tf,
             "presets": cmd_presets, "simulate": cmd_simulate, "export-mjcf": cmd_export,
             "identify": cmd_identify, "diagnose": cmd_diagnose, "compare": cmd_compare,
             "assess": cmd_assess, "study": cmd_study, "drive": cmd_drive, "warm": cmd_warm}


def quiet_stdout() -> None:
    """After a closed pipe: send what is left of stdout to /dev/null, so the interpreter's
    final flush does not complain."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


def _write_json(path: str, result: Result) -> None:
    write_text(path, json.dumps(result.to_json(), indent=2))


def _emit(a: argparse.Namespace, result: Result) -> None:
    """--json: the result's JSON on stdout; --json FILE: written there, the report printed
    and the file named; neither: the report."""
    if a.json == "-":
        print(json.dumps(result.to_json(), indent=2))
    else:
        if a.json:
            _write_json(a.json, result)
        print(result.report(verbose=True) if getattr(a, "verbose", False)
              else result.report())
        if a.json:
            print(f"wrote {a.json}")
    sys.stdout.flush()


def main(argv: list[str] | None = None, loaded: Callable[[], None] | None = None,
         done: Callable[[Result], None] | None = None) -> int:
    """Run one command; exit codes: 0 ok, 2 bad input (one line on stderr), 3 unstable
    configuration, 130 interrupted (Ctrl-C, and whatever the command fails with once it has
    been interrupted), 141 output pipe closed (quietly). `loaded` is called once the
    command's modules are imported, before it runs; `done` with its result, once printed
    (the warm process learns from it: `vtable.warm.server`)."""
    try:
        a = parser().parse_args(argv)
        if (verb := a.command.replace("-", "_")) in verbs.VERBS:
            getattr(verbs, verb)  # its modules imported (`vtable.verbs.__getattr__`)
        if loaded is not None:
            loaded()
        result = _COMMANDS[a.command](a)
        if sigint_seen():  # swallowed on the way (an import's callback): still interrupted
            raise KeyboardInterrupt
        _emit(a, result)
        if done is not None:
            done(result)
        return 0
    except BrokenPipeError:
        quiet_stdout()
        return 141
    except KeyboardInterrupt as e:
        if not getattr(e, "reported", False):
            print("vtable: interrupted", file=sys.stderr)
        return 130
    except Exception as e:
        # once Ctrl-C has reached the command, whatever it then fails with is the interrupt
        # (a library may turn it into an error of its own, unchained: numba, MuJoCo)
        if interrupted(e) or sigint_seen():
            print("vtable: interrupted", file=sys.stderr)
            return 130
        if isinstance(e, UnstableError):
            print(f"vtable: {e}", file=sys.stderr)
            return 3
        if isinstance(e, VtableError):
            print(f"vtable: error: {e}", file=sys.stderr)
            return 2
        raise


if __name__ == "__main__":  # python -m vtable.cli: the same start as the `vtable` command
    import runpy

    runpy.run_module("vtable", run_name="__main__")
