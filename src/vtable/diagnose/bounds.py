"""The declarations a diagnosis names as suspects (issue 18, deliverable 6): calibrated base
parameters at a bound of their `--calibrate` setting in the final model, at one in the
calibrated starting model and still leaning on it, or leaned on in the final model and
moved beyond it by a refit with the bound widened (`pushed_beyond`); and the verdict's
sentence on them."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from vtable.diagnose.calibration import WIDEN, Calibration, bounding_setting
from vtable.diagnose.compare import compare
from vtable.diagnose.model import AT_BOUND, TableModel
from vtable.diagnose.selection import failing
from vtable.diagnose.statistics import held_out_gain, standard_errors


def base_at_bounds(base: dict[str, dict[str, Any]], calibration: Calibration,
                   start: dict[str, dict[str, Any]] | None = None,
                   pushed: list[dict[str, Any]] = ()) -> list[dict[str, Any]]:
    """The declared values the calibrated base ends at a bound of: within `AT_BOUND` of its
    range from the bound, on the fitted scale (the logarithm for a factor bound), and bounded
    by a `--calibrate` setting. `base` is the final model's (`TableModel.base_table`),
    `start` the calibrated starting model's: a value at its bound there, not at it in the
    final model but still in the quarter of its range next to that bound there, is listed
    too (`model` "start": the effects added may stand in for a wrong declaration; a value
    the final model brings back towards its declaration was pushed by the missing effect,
    not by the declaration). `pushed`: the entries (`model` "widened") of the declarations
    the final model leans on that a refit with their bounds widened moved beyond them
    (`bounds.pushed_beyond`). Each: {parameter, model, declared, fitted, bound, side,
    unit, calibrate},
    `calibrate` the --calibrate text of the calibration with this bound widened
    (`Calibration.widened`; the settings already given kept)."""
    out = _at_bounds(base, "final")
    final = {b["parameter"] for b in out}
    out += [b for b in _at_bounds(start or {}, "start") if b["parameter"] not in final
            and b["parameter"] in base
            and _position(b["parameter"], base[b["parameter"]], b["side"]) <= LEANS]
    out += [dict(b) for b in pushed if b["parameter"] not in {a["parameter"] for a in out}]
    for b in out:
        name = bounding_setting(b["parameter"], b["side"])
        wider = getattr(calibration.widened([name]), name)
        b["calibrate"] = (None if wider == getattr(calibration, name) else  # at its widest
                          dataclasses.replace(calibration, **{name: wider}).text())
    return out


#: a final value within this fraction of its range from a bound still leans on it
LEANS = 0.25


def leaning(base: dict[str, dict[str, Any]]) -> list[tuple[str, str]]:
    """(parameter, side) of the base parameters within `LEANS` of a bound a --calibrate
    setting sets (the servo loop's fixed bounds excluded)."""
    out = []
    for key, v in base.items():
        for side in ("lower", "upper"):
            if bounding_setting(key, side) is not None and _position(key, v, side) <= LEANS:
                out.append((key, side))
    return out


def _position(key: str, v: dict[str, Any], side: str) -> float:
    """How far the fitted value of `key` is from its `side` bound, as a fraction of its
    range on the fitted scale (the logarithm for a factor bound); 1 with no such bound."""
    lo, hi = v["bounds"]
    name = bounding_setting(key, side)
    if name is None or not hi > lo:
        return 1.0
    f = math.log if WIDEN[name][0] == "factor" and lo > 0 else (lambda z: z)
    pos = (f(v["fitted"]) - f(lo)) / (f(hi) - f(lo))
    return pos if side == "lower" else 1.0 - pos


def _at_bounds(base: dict[str, dict[str, Any]], model: str) -> list[dict[str, Any]]:
    out = []
    for key, v in base.items():
        lo, hi = v["bounds"]
        for side, bound in (("lower", lo), ("upper", hi)):
            name = bounding_setting(key, side)
            if name is None or not hi > lo:
                continue
            f = math.log if WIDEN[name][0] == "factor" and lo > 0 else (lambda z: z)
            pos = (f(v["fitted"]) - f(lo)) / (f(hi) - f(lo))
            if (pos <= AT_BOUND) if side == "lower" else (pos >= 1 - AT_BOUND):
                out.append({"parameter": key, "model": model, "declared": v["declared"],
                            "fitted": v["fitted"], "bound": bound, "side": side,
                            "unit": v["unit"]})
    return out


def bounds_verdict(at_bounds: list[dict[str, Any]], calibration: Calibration) -> str:
    """The verdict's sentence on a base at its bounds (`base_at_bounds`): which
    declarations the data push beyond their bounds (the suspects), and the --calibrate
    setting that lets them all move."""
    if not at_bounds:
        return ""

    def named(b: dict[str, Any]) -> str:
        u = "" if b["unit"] == "1" else f" {b['unit']}"
        moved = b["fitted"] / b["declared"] - 1 if b["declared"] else float("nan")
        head = f"{b['parameter']} (declared {b['declared']:.4g}{u}, "
        if b["model"] != "widened":
            return head + f"fitted {b['fitted']:.4g}{u} at its {b['side']} bound, {moved:+.1%})"
        return (head + f"moves to {b['fitted']:.4g}{u}, {moved:+.1%}, beyond its {b['side']} "
                f"bound {b['bound']:.4g}{u}; held-out error {b['error_before']:.2%} -> "
                f"{b['error_after']:.2%}, {standard_errors(b['z'])})")

    parts = []
    final = [named(b) for b in at_bounds if b["model"] == "final"]
    widened = [named(b) for b in at_bounds if b["model"] == "widened"]
    start = [named(b) for b in at_bounds if b["model"] == "start"]
    if final:
        parts.append("the calibrated base ends at its bounds: " + ", ".join(final))
    if start:
        parts.append("the calibrated starting model (no effect added) ended at its bounds: "
                     + ", ".join(start) + "; an effect added may stand in for a wrong "
                     "declaration")
    if widened:
        parts.append("the final model leans on its bounds; refitted with them widened: "
                     + ", ".join(widened))
    wider = calibration.widened([bounding_setting(b["parameter"], b["side"])
                                 for b in at_bounds])
    one = len(at_bounds) == 1
    how = (f"--calibrate {wider.text()} lets {'it' if one else 'them'} move"
           if wider != calibration else
           "the bounds are at their widest: the declaration must be corrected")
    return ("; ".join(parts) + "; the data push "
            + ("this declaration" if one else "these declarations")
            + " beyond the calibration's bounds, so " + ("it is" if one else "they are")
            + f" the suspect: {how}")


def leaning_start(diagnoser, start) -> tuple | None:
    """When a diagnosis's calibrated starting model `start` leans on bounds
    (`base_at_bounds`): the calibration with them widened and the parameters; the starting
    model refitted with it (a job of the first round) gives the baseline a candidate effect
    must also beat (SELECTION: an effect is not added in place of a wrong declaration);
    None when nothing leans or the bounds are at their widest."""
    lean = base_at_bounds(diagnoser.base_table(start), diagnoser.calibration)
    names = [bounding_setting(b["parameter"], b["side"]) for b in lean]
    wider = diagnoser.calibration.widened([n for n in names if n is not None])
    if not lean or wider == diagnoser.calibration:
        return None
    return wider, [b["parameter"] for b in lean]


def widened(diagnoser, lean: tuple, fitted) -> tuple:
    """(wider calibration, the parameters, the refit's held-out predictions) from the
    starting model's refit `fitted` (a `workers.CandidateFit`) with `lean`'s bounds
    (`leaning_start`); the diagnosis's notes say so."""
    wider, names = lean
    diagnoser.notes.append(f"the calibrated starting model leans on its bounds "
                           f"({', '.join(names)}): candidates must also beat it refitted "
                           f"with --calibrate {wider.text()}")
    return wider, names, diagnoser.predict(fitted.physics)


def pushed_beyond(dg, current, err: float, predictions) -> list[dict[str, Any]]:
    """The declarations the final model `current` of diagnoser `dg` leans on (`leaning`:
    within a quarter of their range from a bound a --calibrate setting sets, short of
    `AT_BOUND`) that the data push beyond it: `current` refitted with those bounds widened
    moves each beyond its old bound, and the gain of that refit over `current` (held-out
    error `err`, channels `predictions`) passes `SELECTION`'s statistical criteria (a wrong
    declaration, e.g. a platen mass 20 % off, whose error the free servo loop half
    absorbs, so the fit stops short of the bound against the prior). Each as a
    `base_at_bounds` entry with `model` "widened", the refit's value as `fitted` and the
    gain's figures; each refit tried is said in `dg.notes`."""
    base = dg.base_table(current)
    at = {b["parameter"] for b in base_at_bounds(base, dg.calibration)}
    lean = [(k, side) for k, side in leaning(base) if k not in at]
    wider = dg.calibration.widened([n for k, side in lean
                                    if (n := bounding_setting(k, side)) is not None])
    if not lean or wider == dg.calibration:
        return []
    refit = TableModel(start=current, stop=dg._stop, calibration=wider,
                       choose=False).fit(dg.campaign)
    pred = dg.predict(refit.physics_)
    gain = held_out_gain(predictions, pred, dg.runs, dg.campaign.noise)
    moved = dg._model(wider).base_table(refit.physics_)
    after = compare(pred, dg.runs, scored="held", floor=dg.floor).error
    fails = failing(gain)
    out = []
    for k, side in lean:
        lo, hi = base[k]["bounds"]
        v = moved[k]["fitted"]
        beyond = v < lo if side == "lower" else v > hi
        dg.notes.append(
            f"the final model leans on the {side} bound of {k} ({base[k]['fitted']:.4g} "
            f"{base[k]['unit']}); refitted with --calibrate {wider.text()} it moves to "
            f"{v:.4g} {base[k]['unit']}, held-out error {err:.2%} -> {after:.2%} ("
            + ("the data push it beyond its bound" if beyond and not fails else
               "; ".join(fails) if beyond else "within its bound") + ")")
        if beyond and not fails:
            out.append({"parameter": k, "model": "widened", "declared": base[k]["declared"],
                        "fitted": v, "bound": lo if side == "lower" else hi, "side": side,
                        "unit": base[k]["unit"], "error_before": err, "error_after": after,
                        "z": gain.z})
    return out
