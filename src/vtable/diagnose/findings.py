"""A diagnosis as a lab engineer reads it: one headline (at most `HEADLINE_MAX` characters:
what was added, the held-out error before and after, the noise floor, the bound and the
black box), then findings, each what was seen, on which runs, its numbers and what to do
(issue 32, deliverable 4; `headline` and `findings` of docs/diagnosis-json.md). The
statistics behind them stay in the JSON and the verdict (`vtable diagnose --verbose`)."""

from __future__ import annotations

import math
from typing import Any

from vtable.diagnose.noise import NOISE_FACTOR, within_noise
from vtable.diagnose.prose import params_text
from vtable.diagnose.reading import SAID
from vtable.diagnose.selection import implausibility, near_miss, prior_cost
from vtable.display import run_family
from vtable.effects.registry import get as effect
from vtable.effects.registry import names

#: the headline's length at most (characters)
HEADLINE_MAX = 200

#: a model whose held-out error is this many times the black box's leaves dynamics the data
#: hold unmodelled (the black box has far more unknowns, so 1 is not a bound: a physics model
#: of the right form should reach it)
REFERENCE_FACTOR = 1.0


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:.3g} %"


def headline(added: list[str], start: float | None, final: float | None, floor: float,
             bound: float | None, reference: float | None, interrupted: bool = False
             ) -> str:
    """One sentence: the effects added, the error before -> after, against the floor, the
    bound and the black box; at most `HEADLINE_MAX` characters (effects beyond what fits
    are counted, not named)."""
    tail = f"noise floor {_pct(floor)}"
    if bound is not None:
        tail += f", bound {_pct(bound)}"
    if reference is not None:
        tail += f", black box {_pct(reference)}"
    if final is None:
        return ("interrupted before the starting model was fitted" if interrupted
                else "no model was fitted")[:HEADLINE_MAX]
    errors = f"{_pct(start)} -> {_pct(final)}" if added else _pct(final)
    verdict = ("within the noise" if within_noise(final, floor)
               else f"{final / floor:.1f} x the floor" if floor > 0 else "")
    lead = "interrupted; " if interrupted else ""
    names = list(added)
    for keep in range(len(names), -1, -1):
        what = ", ".join(names[:keep]) + (f" +{len(names) - keep} more" if keep < len(names)
                                          else "")
        text = (f"{lead}added {what}: {errors}" if added else f"{lead}nothing added: {errors}")
        text += f" ({tail})" + (f"; {verdict}" if verdict else "")
        if len(text) <= HEADLINE_MAX:
            return text
    return text[:HEADLINE_MAX]


def finding(kind: str, what: str, action: str, runs: list[str] | None = None,
            numbers: dict[str, Any] | None = None) -> dict[str, Any]:
    """One finding as docs/diagnosis-json.md holds it."""
    return {"kind": kind, "runs": list(runs or []), "what": what,
            "numbers": dict(numbers or {}), "action": action}


def findings(d, sensors=(), notches: dict | None = None, plants=(),
             shown: dict | None = None, commands=()) -> list[dict[str, Any]]:
    """The findings of a `Diagnosis` `d` (its rounds, unexplained residual, limits,
    declarations at their bounds, interruption), the campaign's acceleration channels that
    disagree with its displacement (`sensors`: `sensors.SensorCheck`) and the notches of
    x_t/x_c that move within a run (`notches`: run -> (first Hz, last Hz, window s)) and
    the pairs of runs that do not hold one plant (`plants`: `plants.PlantDifference`), and
    what the runs show of effects the final model does not hold (`shown`: effect ->
    (values, where from), `Effect.evidence`) and the runs whose command column is not
    the command their table followed (`commands`: `command_check.CommandOffset`,
    `CommandScale`)."""
    out = []
    if d.interrupted:
        out.append(finding("interrupted", f"the diagnosis was interrupted after round "
                           f"{len(d.rounds)}", "run it again to the end"))
    model = list(d.start_effects)  # the model's effects after each step (`--with`)
    for r in d.steps():
        if isinstance(r, dict):  # the force reading kept
            out.append(_reading_finding(r))
            continue
        model = [e for e in model if e not in r.removed]
        if r.added:
            model.append(r.added)
            c = next((c for c in r.ranking if c.effect == r.added), None)
            params = {} if c is None else {k: float(v) for k, v in c.params.items()
                                           if isinstance(v, (int, float))}
            out.append(finding(
                "effect_added", f"{r.added} lowers the held-out error {_pct(r.before)} -> "
                f"{_pct(r.error)}", f"keep it in the model (--with {','.join(model)})",
                numbers={"error_before": r.before, "error_after": r.error, **params}))
        for e, why in r.removed.items():
            out.append(finding("effect_removed", f"{e} removed: {why}", "leave it out"))
    lim = d.limits
    if lim is not None and d.final_error is not None:
        out += _limit_findings(d, lim)
    for c in commands:
        out.append(finding(c.kind, c.text(), c.action(), runs=[c.run], numbers=c.numbers()))
    for b in d.base_at_bounds:
        moved = b["fitted"] / b["declared"] - 1 if b["declared"] else None
        out.append(finding(
            "declaration_at_bound", f"{b['parameter']} (declared {b['declared']:.4g} "
            f"{b['unit']}) ends at its {b['side']} bound {b['bound']:.4g}",
            f"check the declaration; --calibrate {b['calibrate']} lets it move"
            if b.get("calibrate") else "the bound is at its widest: correct the declaration",
            numbers={"declared": b["declared"], "fitted": b["fitted"], "bound": b["bound"],
                     "change": moved}))
    # a final model within the noise reproduces every channel: what the checks on the runs
    # pointed at (two sensors that disagree, an effect's evidence) it explains without
    explained = d.unexplained is None and d.final_error is not None
    for c in () if explained else sensors:
        out.append(finding("sensor", c.text(), "check the acceleration channel's sensor, "
                           "its mount and its calibration against the displacement",
                           runs=[c.run]))
    for p in plants:
        out.append(finding("plants", p.text(), _plants_action(d), runs=list(p.runs),
                           numbers={"z2_mean": p.z2_mean, "z_max": p.z_max, "lines": p.lines,
                                    "at_hz": p.at_hz, "relative": p.relative}))
    if getattr(d, "states", None):
        out.append(_states_finding(d.states, d.states_declared))
    for name, (values, where) in ({} if explained else shown or {}).items():
        if name in d.final_effects:
            continue
        runs = getattr(d, "runs", None)
        vals = params_text(name, values, run_family(runs[0]) if runs else "imperial", ".3g")
        out.append(finding(
            "shown", f"the runs show {name} ({vals}; {where}) that the final model does not "
            "hold", f"the diagnosis fitted {name} from there and did not add it: start from it "
            f"(--with {name}) to see it fitted in, or declare what it stands for (an "
            "undocumented specimen in [specimen])",
            numbers={k: float(v) for k, v in values.items()}))
    missed = _not_added(d)
    out += [f for _, f in missed]
    drifting = [e for e in names() if getattr(effect(e), "accumulates", False)]
    held = [e for e in d.final_effects if e in drifting]
    blocked = [e for e, _ in missed if e in drifting]
    tried = [e for e in drifting if any(c.effect == e and c.gain is not None and not (
        c.screened or c.not_fitted) for r in d.rounds for c in r.ranking)]
    for run, (f1, f2, w) in (notches or {}).items():
        out.append(finding(
            "softening", f"x_t/x_c's notch moves {f1:.2f} -> {f2:.2f} Hz within the run: the "
            f"specimen's stiffness changes by {(f2 / f1) ** 2 - 1:+.0%}",
            f"the final model follows it with {', '.join(held)}" if held else
            f"the diagnosis fitted {', '.join(blocked)} to it and did not add it: see the "
            "not_added finding" if blocked else
            f"the diagnosis fitted {', '.join(tried)} to it, which did not explain enough of it "
            "(its ranking, --verbose): write an effect of another form of change, or fit the "
            "run's first part alone" if tried else
            "no time-invariant model follows it: add an effect whose stiffness changes during "
            f"the run ({', '.join(drifting) or 'your own'}: it acts on the declared "
            "specimen, so where the runs declare none, declare the one whose notch moves, "
            "e.g. the resonator fitted in its place), or fit the run's first part alone",
            runs=[run], numbers={"first_hz": f1, "last_hz": f2, "window_s": w}))
    return out


def _not_added(d) -> list[tuple[str, dict[str, Any]]]:
    """The candidates of the final model's rounds (the last ones, which added nothing) whose
    held-out gain the selection's statistics take (`selection.near_miss`) but which were not
    added — the last round's first, each round's best first: what each would have bought and
    what stopped it (its parameters at a bound, their distance from their defaults, a
    declaration that explains as much). None when the final model is within the noise, and
    none when the diagnosis then split the runs into a state each (its gains were measured
    on the model before the split); an effect added and removed is said by its removal.
    Returns (effect, finding) pairs."""
    if d.unexplained is None or (getattr(d, "states", None)
                                 and not getattr(d, "states_declared", False)):
        return []
    tail = []
    for r in reversed(d.rounds):
        if r.added is not None:
            break
        tail.append(r)
    out, seen = [], set(d.final_effects) | {e for r in d.rounds for e in r.removed}
    for r in tail:
        for c in sorted(r.ranking, key=lambda c: c.score):
            if c.effect in seen or not near_miss(c):
                continue
            seen.add(c.effect)
            failing = c.failing()
            why = [f.removeprefix(f"{c.effect}.") for f in c.blocking] + failing[:1]
            if c.stand_in:
                why.append("the starting model refitted with its leaning declarations widened "
                           "explains as much")
            bound = [f.removeprefix(f"{c.effect}.").split(" at its ")[0]
                     for f in c.blocking if " bound (" in f]
            far = [w.split(" (", 1)[0] for w, z in implausibility(
                c.effect, c.physics.effects.get(c.effect, {}), c.table) if abs(z) > 1]
            # the statistics fail only with its distance from the defaults charged
            charged = bool(failing) and far and prior_cost(c.gain, c.physics, c.effect,
                                                           c.table) > 0
            action = ("a declaration explains as much: correct the declarations at their "
                      "bounds (their findings)" if c.stand_in else
                      f"it ends at the edge of its range ({', '.join(bound)}): the runs may "
                      "hold another form of it, an effect of your own (--effects-from FILE)"
                      if bound else
                      f"its fitted values are far from their defaults ({'; '.join(far)}): "
                      "where a source of its own (a test, a datasheet; not this fit) gives "
                      "such values for your table or specimen, an effect of your own with "
                      "them as defaults (--effects-from FILE) is not charged for them; else "
                      "it stands in for something else" if charged else
                      "not added on this evidence: its flags and statistics are in the "
                      "ranking (--verbose)")
            if getattr(effect(c.effect), "accumulates", False):
                action += ", or split the run where the specimen changed"
            g = c.gain
            share = f"{g.share:.0%}" if math.isfinite(g.share) else "all"
            params = {k: float(v) for k, v in c.params.items() if isinstance(v, (int, float))}
            out.append((c.effect, finding(
                "not_added", f"{c.effect} would lower the held-out error {_pct(r.error)} -> "
                f"{_pct(c.error_after)} ({share} of the systematic residual) but was not "
                f"added: {'; '.join(why) or 'see its ranking (--verbose)'}", action,
                numbers={"error_before": r.error, "error_after": c.error_after, "z": g.z,
                         "share": g.share, **params})))
    return out


#: what to do where the runs declare states but no specimen to fit in each
NO_SPECIMEN = ("the runs declare no specimen ([specimen] kind \"none\"): the states have "
               "nothing of their own to fit; declare the specimen that changed (its kind and "
               "nominal values) so that each state gets its own, or diagnose the runs apart")


def _plants_action(d) -> str:
    """What to do about two runs that do not hold one plant: the states the diagnosis
    split the runs into, the states they declare (with or without a specimen to fit in
    each), or none."""
    states = getattr(d, "states", None) or {}
    if states and not getattr(d, "states_declared", False):
        return ("fitted with a specimen state per run (the states finding); declare each "
                "state ([specimen] state) in the run files")
    if states and not any(r["specimen"] for r in states.values()):
        return NO_SPECIMEN
    if states:
        return ("the states' specimens, fitted apart, do not follow the difference: runs of "
                "one state that differ (declare the states finer), a change beyond the "
                "specimen (the table, a sensor), or an amplitude dependence no effect in the "
                "model follows")
    return ("a specimen that changed between the runs: declare each state ([specimen] "
            "state) and diagnose them apart; or an amplitude dependence no effect in the "
            "model follows")


def _states_finding(states: dict[str, dict[str, Any]], declared: bool) -> dict[str, Any]:
    """The specimen's fitted parameters in each state (`states.state_rows`)."""
    def text(s: str, row: dict[str, Any]) -> str:
        sp = row["specimen"]
        f = [v for k, v in sp.items() if k.endswith("frequency_hz")]
        xi = [v for k, v in sp.items() if k.endswith("damping")]
        return (f"{s} ({len(row['runs'])} run{'s' if len(row['runs']) != 1 else ''}): "
                + (f"{'/'.join(f'{v:.3g}' for v in f)} Hz" if f else "no mode")
                + (f", damping {'/'.join(f'{v:.2%}' for v in xi)}" if xi else ""))

    what = (("the runs' declared states" if declared else "a state per run") + ", fitted: "
            + "; ".join(text(s, r) for s, r in states.items()))
    action = (("compare the states' specimens: the change between them is the specimen's"
               if any(r["specimen"] for r in states.values()) else NO_SPECIMEN)
              if declared else "the runs do not hold one specimen: declare each run's state "
              "([specimen] state) so that runs of one state share it")
    numbers = {f"{s}.{k}": float(v) for s, r in states.items()
               for k, v in r["specimen"].items()}
    return finding("states", what, action, runs=[x for r in states.values() for x in r["runs"]],
                   numbers=numbers)


def _limit_findings(d, lim) -> list[dict[str, Any]]:
    """What the model leaves that a time-invariant model could still fit, what none can,
    and where a black box does better."""
    out = []
    floor = d.noise_floor
    worse = [g for g in lim.groups if g.reference is not None and g.error is not None
             and g.error > REFERENCE_FACTOR * g.reference and g.error > NOISE_FACTOR * g.noise]
    if worse:
        out.append(finding(
            "below_reference", "a black box of the command predicts better than the model on "
            + ", ".join(f"{g.run} {g.group} ({_pct(g.error)} vs {_pct(g.reference)})"
                        for g in worse[:4]) + (f" and {len(worse) - 4} more"
                                               if len(worse) > 4 else ""),
            "dynamics the data hold are missing: look at the within-reach part and the worst "
            "band; an effect of the right form (the catalog's, or your own) should reach it",
            runs=sorted({g.run for g in worse}),
            numbers={"model": lim._mean("error"), "reference": lim.reference}))
    if d.unexplained is None:
        return out
    out += _part(lim, "within_reach", NOISE_FACTOR * floor,
                 "a time-invariant model could still fit ",
                 "a missing linear effect (or a change between training and held-out parts): "
                 "try a catalog effect with --effects, or write your own", {})
    out += _part(lim, "beyond", NOISE_FACTOR * floor,
                 "no time-invariant model of the command can fit ",
                 "nonlinearity, a change during the run or a disturbance: a nonlinear or "
                 "time-varying effect, or runs split where the specimen changed",
                 {"bound": lim.bound})
    return out


def _part(lim, name: str, above: float, lead: str, action: str,
          numbers: dict[str, Any]) -> list[dict[str, Any]]:
    """One finding (kind `name`) naming the groups whose part `name` of the model's error
    (`limits.GroupLimit`) is above `above`, or none."""
    groups = [g for g in lim.groups if (getattr(g, name) or 0) > above]
    if not groups:
        return []
    what = lead + ", ".join(f"{g.run} {g.group} {_pct(getattr(g, name))}" for g in groups[:4])
    return [finding(name, what, action, runs=sorted({g.run for g in groups}),
                    numbers={name: getattr(lim, name), **numbers})]


def _reading_finding(reading: dict[str, Any]) -> dict[str, Any]:
    """The finding of the force channels' other reading a diagnosis kept
    (`reading.force_reading`)."""
    found = reading["found"]
    return finding(
        "force_measured", f"the force channels measure {SAID[found]}, not "
        f"{SAID[reading['assumed']]} as assumed (the runs do not declare it): held-out error "
        f"{_pct(reading['error_before'])} -> {_pct(reading['error_after'])}",
        f"declare force_measured = \"{found}\" in the runs' [table.horizontal]",
        numbers={k: reading[k] for k in ("error_before", "error_after", "z")})
