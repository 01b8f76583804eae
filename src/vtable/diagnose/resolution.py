"""The reduced model's resolution: how closely it reproduces the virtual table (the MuJoCo
multibody table with its controllers, `vtable.models.virtual`) with each catalog effect in,
measured, so that the selection (`vtable.diagnose.selection`) never takes a patch of that
model-form difference for a missing effect (issue 18, deliverable 4).

An effect's *agreement* r_e is the diagnosis's own error measure (`ERROR_DEFINITION`:
the mean over runs and channel groups of the squared NRMS error, on the held-out last
40 % of every run at the analysis rate; r_e is its square root) between the reduced model
(`ReducedModel.predict`) and noise-free virtual-table runs of the same physics: the base
(nominal open loop, eq 6.15 with Table B.5's constants; the SDOF frame of §9.2) with the
effect in at its default dose, on `COMMANDS` (the tests' campaign: random 0-25 Hz at 0.05
and 0.15 in, §9.2 El Centro). Both models carry the same parameters: nothing is fitted,
so r_e bounds what recalibrating the base or a patch can remove of the difference.

`resolution(effects)` of a model is the base's figure and each present effect's excess
over it added on the squared scale,

    r² = r_base² + Σ_e max(r_e² - r_base², 0),

because every r_e already holds the base's own difference, and the differences different
effects add are different signals: on this scale they add as sensor noise and a
systematic error do (the maximum would credit a model with two effects the resolution of
its worse one). `python -m vtable.diagnose.resolution` measures every registered catalog
effect and writes `resolution.toml` beside this module (each figure with how and when); an
effect without a shipped figure (a user's) is measured on the fly the same way (about a
second) and, when its model cannot be built on the SDOF frame, taken at the largest
shipped figure.
"""

from __future__ import annotations

import datetime
import functools
import math
import subprocess
import sys
import tomllib
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from vtable.diagnose.groups import group_prediction, group_signal, run_groups
from vtable.diagnose.sampling import analysis_run, segments
from vtable.diagnose.statistics import nrms
from vtable.effects.registry import BUILT_IN, STANDARD
from vtable.errors import VtableError
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.params import presets
from vtable.signals import make_command

#: the shipped figures (`python -m vtable.diagnose.resolution` writes it)
DATA = Path(__file__).with_name("resolution.toml")
BASE = "base"
SPECIMEN = "sdof_frame"
#: the commands the agreement is measured on: name -> make_command's arguments
COMMANDS = {"random_small": ("random", {"duration": 11.0, "band": (0.0, 25.0),
                                        "peak_in": 0.05, "seed": 1}),
            "random_large": ("random", {"duration": 11.0, "band": (0.0, 25.0),
                                        "peak_in": 0.15, "seed": 2}),
            "el_centro": ("earthquake", {"peak_in": 4.0})}
HOW = ("sqrt of the mean over runs and channel groups of the squared NRMS difference "
       "between the reduced model and noise-free virtual-table runs (held-out last 40 %, "
       f"analysis rate), the {SPECIMEN} specimen, the base plus the effect at its default "
       f"dose, commands: {', '.join(COMMANDS)} (vtable.diagnose.resolution.COMMANDS)")


@functools.cache
def _commands() -> tuple:
    return tuple(make_command(kind, **kw) for kind, kw in COMMANDS.values())


def agreement(effects: Mapping[str, Mapping[str, float]]) -> tuple[float, str, float]:
    """The reduced model's agreement with the virtual table for the base plus `effects`
    ({name: parameters}; {} each for the default dose): (r, the worst channel group, its
    NRMS on the run where it is worst). Noise-free; r as `ERROR_DEFINITION` (see the module
    docstring)."""
    from vtable.sim import simulate  # the multibody table: only when measuring, not on import

    ph = Physics(nominal_open_loop(), presets.specimen(SPECIMEN),
                 {k: dict(v) for k, v in effects.items()})
    e2, worst = [], (BASE, 0.0)
    for cmd in _commands():
        run = analysis_run(simulate(ph, cmd))
        pred = ReducedModel(ph).predict(run)
        _, ho = segments(run)
        for g in run_groups(run):
            y, yhat = group_signal(run, g), group_prediction(pred, run, g)
            if y is None or yhat is None or not np.any(y[ho]):
                continue
            e = nrms(yhat[ho], y[ho])
            e2.append(e * e)
            worst = max(worst, (g, e), key=lambda w: w[1])
    return float(np.sqrt(np.mean(e2))), worst[0], float(worst[1])


@functools.cache
def shipped() -> dict[str, float]:
    """The shipped figures: effect (and "base") -> r."""
    try:
        data = tomllib.loads(DATA.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise VtableError(f"{DATA}: cannot read the model's resolution figures ({e}); "
                          "regenerate them: python -m vtable.diagnose.resolution") from None
    return {k: float(v["nrms"]) for k, v in data["agreement"].items()}


@functools.cache
def figure(name: str) -> float:
    """An effect's agreement r_e: shipped, else measured now at its default dose (a user's
    effect), else (its model cannot be built on the SDOF frame) the largest shipped one."""
    known = shipped()
    if name in known:
        return known[name]
    try:
        return agreement({name: {}})[0]
    except VtableError:
        return max(known.values())


def resolution(effects: Iterable[str] = ()) -> float:
    """The resolution of the reduced model with `effects` in: sqrt(r_base² + Σ_e
    max(r_e² - r_base², 0)) (module docstring)."""
    b = shipped()[BASE]
    return math.sqrt(b * b + sum(max(figure(e) ** 2 - b * b, 0.0) for e in effects))


def _commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, cwd=Path(__file__).parent, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def measure(names: Iterable[str] = BUILT_IN) -> str:
    """The TOML text of the figures of the base and each of `names` (measured now), with
    the standard table's pair measured together against `resolution`'s sum."""
    lines = ["# The reduced model's agreement with the virtual table, per catalog effect at its",
             "# default dose (vtable.diagnose.resolution). Generated: do not edit; regenerate",
             "# with `python -m vtable.diagnose.resolution`.", "",
             f"how = {_quote(HOW)}",
             f"when = {_quote(datetime.date.today().isoformat())}",
             f"commit = {_quote(_commit())}", "", "[agreement]"]
    figures = {}
    for name in (BASE, *names):
        r, g, w = agreement({} if name == BASE else {name: {}})
        figures[name] = r
        lines.append(f"{name} = {{ nrms = {r:.6f}, worst_group = {_quote(g)}, "
                     f"worst_nrms = {w:.6f} }}")
        print(f"{name:<30} {r:.4%}  (worst: {g} {w:.3%})", file=sys.stderr)
    pair = STANDARD
    if set(pair) <= set(figures):
        r, _, _ = agreement({e: {} for e in pair})
        b = figures[BASE]
        summed = math.sqrt(b * b + sum(max(figures[e] ** 2 - b * b, 0.0) for e in pair))
        lines += ["", "# the standard table's pair measured together, and the rule's sum",
                  "[check]", f"effects = [{', '.join(map(_quote, pair))}]",
                  f"measured = {r:.6f}", f"summed = {summed:.6f}"]
        print(f"{' + '.join(pair)}: measured {r:.4%}, summed {summed:.4%}", file=sys.stderr)
    return "\n".join(lines) + "\n"


def _quote(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def main() -> None:
    """Measure every catalog effect and write `DATA`."""
    DATA.write_text(measure(), encoding="utf-8")
    print(f"wrote {DATA}", file=sys.stderr)


if __name__ == "__main__":
    main()
