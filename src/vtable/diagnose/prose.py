"""Where a model fails, in words and numbers: the worst channel groups and bands, the
amplitude trend, the worst time window, and whether a residual is left unexplained
(`noise.UNEXPLAINED_RULE`); an effect's values as the user reads them (`params_text`)."""

from __future__ import annotations

from typing import Any

from vtable import display
from vtable.diagnose.groups import short
from vtable.diagnose.noise import within_noise
from vtable.diagnose.statistics import Comparison
from vtable.display import amplitude
from vtable.effects.registry import get as effect
from vtable.params.specimen import NoSpecimen
from vtable.runs.model import Run
from vtable.units import to_si


def linear_model(runs: list[Run]) -> str:
    """What the linear model of `runs` holds, as the texts and reports name it: "servo loop
    + specimen", or "servo loop + bare platen" on runs that declare no specimen
    ([specimen] kind = "none")."""
    bare = bool(runs) and all(isinstance(r.specimen(), NoSpecimen) for r in runs)
    return "servo loop + bare platen" if bare else "servo loop + specimen"


def mils(x_m: float) -> str:
    """A command amplitude in metres as mils (1 mil = 0.001 in = 25.4 µm), the number
    only (`vtable.display.amplitude` gives it with its unit, mil or mm)."""
    return amplitude(x_m).removesuffix(" mil")


def amplitude_trend(cmp: Comparison, group: str | None = None) -> str:
    """How a group's (or the mean) error changes with the command's RMS span across runs."""
    pts = []
    for name, a, e in cmp.amplitude:
        if group is not None:
            e = cmp.per_run.get(name, {}).get(group)
        if e is not None:
            pts.append((a, e))
    if len({round(a, 9) for a, _ in pts}) < 2:
        return "one command amplitude only (no amplitude trend can be read)"
    pts.sort()
    (a0, e0), (a1, e1) = pts[0], pts[-1]
    span = (f"{e0:.1%} at {amplitude(a0, cmp.display)} rms, "
            f"{e1:.1%} at {amplitude(a1, cmp.display)} rms")
    if e1 > 1.25 * e0:
        return f"largest at the largest spans ({span})"
    if e0 > 1.25 * e1:
        return f"largest at the smallest spans ({span})"
    return f"no clear amplitude trend ({span})"


def unexplained(cmp: Comparison) -> dict[str, Any] | None:
    """None when cmp.error <= NOISE_FACTOR x the noise floor, else the ratio and where the
    residual lives (UNEXPLAINED_RULE)."""
    floor = cmp.noise_floor
    if within_noise(cmp.error, floor):
        return None
    ratio = cmp.error / floor if floor > 0 else float("inf")
    return {"ratio_to_floor": ratio, "where": residual_location(cmp)}


def residual_location(cmp: Comparison) -> str:
    """'<group>, <band>, <amplitude trend>, <time window>' of a comparison made with
    detail=True; what could not be read is said."""
    worst = cmp.worst_groups(1)
    if not worst:
        return "no channel group was scored"
    g, e = worst[0]
    wb = cmp.worst_band(g)
    band = f"worst band {wb[0]} ({wb[1]:.1%})" if wb else "no band resolved (no coherent band)"
    if cmp.windows:
        name, t0, t1, ew = max(cmp.windows, key=lambda x: x[3])
        window = f"worst 2 s window {t0:.1f}-{t1:.1f} s of {short(name)} ({ew:.1%})"
    else:
        window = "no time window located (runs shorter than 2 s)"
    return f"{g} ({e:.1%}), {band}, {amplitude_trend(cmp, g)}, {window}"


def localisation_text(cmp: Comparison) -> str:
    """Where the model fails, in words and numbers."""
    parts = []
    worst = cmp.worst_groups(2)
    if worst:
        parts.append("largest errors in " + ", ".join(f"{g} ({e:.1%})" for g, e in worst))
        wb = cmp.worst_band(worst[0][0])
        if wb:
            parts.append(f"{worst[0][0]} worst at {wb[0]} ({wb[1]:.1%})")
    if len(cmp.amplitude) > 1:
        amp = sorted(cmp.amplitude, key=lambda x: x[1])
        parts.append("by command amplitude: " + ", ".join(
            f"{e:.1%} at {amplitude(a, cmp.display)} rms" for _, a, e in amp))
    if cmp.windows:
        name, t0, t1, e = max(cmp.windows, key=lambda x: x[3])
        parts.append(f"worst 2 s window {t0:.1f}-{t1:.1f} s of {short(name)} ({e:.1%})")
    parts.append(f"noise floor {cmp.noise_floor:.1%}")
    return "; ".join(parts)




def nothing_added(ranking: list, err: float, widened: tuple | None) -> str:
    """Why a round added nothing: its best candidate (`ranking[0]`, a `Candidate`), the
    criteria it fails or the flags that keep it out, or the wrong declaration (`widened`:
    the calibration with the leaning bounds widened and what moved) it would stand in for."""
    top = ranking[0]
    what = (f"the best candidate ({top.effect}) would change the held-out error "
            f"{err:.2%} -> {top.error_after:.2%}")
    if top.stand_in and not top.failing() and not top.blocking:
        reason = (f"{what}, but the starting model with its bounds widened (--calibrate "
                  f"{widened[0].text()}: {', '.join(widened[1])} move) explains as much: "
                  f"{'; '.join(top.stand_in)} over it; it would stand in for a wrong "
                  "declaration")
    elif top.failing():
        reason = f"{what}, not added: " + "; ".join(top.failing())
    else:
        reason = f"{what}, but it is not added on that evidence: " + "; ".join(top.blocking)
    passing = [c for c in ranking if not c.failing()]
    if passing and top.failing():
        reason += ("; the candidates whose gain would count are not sound fits: "
                   + "; ".join(f"{c.effect}: {'; '.join(c.blocking)}" for c in passing))
    return reason + " (the base recalibrated with every candidate)"


def base_lines(base: dict[str, Any], indent: str = "") -> list[str]:
    """The calibrated base: declared -> fitted within its bounds, one line each."""
    if not base:
        return []
    out = [f"{indent}base (declared -> fitted, bounds):"]
    for k, v in base.items():
        u = "" if v["unit"] == "1" else f" {v['unit']}"
        lo, hi = v["bounds"]
        moved = (v["fitted"] / v["declared"] - 1) if v["declared"] else float("nan")
        out.append(f"{indent}  {k:<28} {v['declared']:.4g} -> {v['fitted']:.4g}{u} "
                   f"({moved:+.1%}; bounds {lo:.4g}-{hi:.4g})")
    return out


def params_text(name: str, params: dict[str, float], fam: str, spec: str = ".4g") -> str:
    """An effect's fitted parameters (in its units) as the user reads them: 'friction =
    2.98 kip' for a run in the report's units, '13.3 kN' for a metric one
    (`vtable.display`)."""
    units_of = {p.name: p.unit for p in effect(name).params}
    return ", ".join(f"{k} = {display.quantity(to_si(v, units_of[k]), units_of[k], fam, spec)}"
                     if k in units_of else f"{k} = {v:{spec}}" for k, v in params.items())
