"""When a candidate effect's held-out gain over the calibrated current model counts as a
missing effect rather than noise or a patch; the loop (`engine`) applies it.

Selection rule (`SELECTION`), on the held-out segments and on the squared scale where
sensor noise and a systematic error add (e² = mean over runs and channel groups of the
squared NRMS error; the noise alone costs f², the current model's systematic residual is
e² - f²; `statistics.held_out_gain`). The candidate's e² is first charged its parameters'
implausibility (`prior_cost`: each fitted parameter's distance from its declared default,
in units of `PLAUSIBLE`, squared, times `PRIOR_SHARE` of the current model's systematic
residual), so that a value far outside its physical range buys that distance with evidence
(a Gaussian prior on the log of the parameter, as the calibration's priors on the base:
`vtable.diagnose.calibration`). It is charged against the systematic residual, not the
noise: a patch of a model-form difference is systematic too, and stands any number of
standard errors above the noise; what it cannot do is explain most of the residual with a
value 30 times its physical one (at 3 σ, 48 % of the residual is charged, so it must remove
68 % to meet criterion 2). A
candidate is added only if its gain e²_current - e²_candidate, so charged,

1. exceeds `Z_NOISE` (5) standard errors of what the held-out noise produces between the two
   predictions: both were fitted on the training segments, so the held-out noise enters the
   gain only as 2 n·(ŷ_c - ŷ)/||y||², Gaussian with a variance the noise σ of every group
   gives (a likelihood-ratio test against the noise floor; white noise at the analysis rate);
2. removes at least `MIN_SHARE` (20 %) of the current model's systematic residual: the
   current model is itself calibrated, so this is what the effect explains that recalibrating
   the base cannot, and a small patch of a model-form difference is not a missing effect
   (`SHOWN_SHARE`, 5 %, for an effect the runs show by a check of their own,
   `Effect.evidence`, fitted within one prior width of what they show: that check, not
   the share, tells it from a patch);
3. is at least `NOISE_SHARE` (5 %) of what the noise alone costs (f²): refitting the base and
   an effect to other noise moves a held-out error by less;
4. is at least r², the squared resolution of the reduced model with the candidate in
   (`vtable.diagnose.resolution`: the base's and each present effect's measured agreement
   with the virtual table): the most a patch of the model-form difference can remove;

(6) when the calibrated starting model leans on a bound (`bounds.base_at_bounds`), its gain
over the starting model refitted with those bounds widened (`Calibration.widened`) passes
(1)-(4) too: an effect that only stands in for a wrong declaration is not added, and the
verdict names the declaration (`engine`);

and (5) its fit is sound: no fitted effect parameter within 1 % of a bound (fitted scale),
correlated beyond 0.95 with a base parameter, or without influence on the data
(Gauss-Newton covariance at the solution), and the effect acts in the fitted model's own
predictions of the runs (`Effect.unseen`: a storey_yield whose yield drift no run reaches
is a smooth softening bought with an extrapolated u_y). A candidate failing (5) is flagged in the
ranking and not added on that evidence; the next sound one may be. Base parameters at a
bound are flagged too but do not block: they say the model still lacks something.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from vtable.diagnose.resolution import resolution
from vtable.diagnose.statistics import Gain
from vtable.effects.registry import get as effect
from vtable.models.physics import Physics

Z_NOISE = 5.0  # the held-out gain must stand 5 standard errors above what noise produces ...
MIN_SHARE = 0.2  # ... remove 20 % of the current model's systematic residual (squared) ...
#: ... be 5 % of what the noise alone costs (f²) and at least the squared resolution of the
#: reduced model with the candidate in (`resolution.resolution`)
NOISE_SHARE = 0.05
#: ... or `SHOWN_SHARE` for an effect the runs show by a check of their own whose fit lies
#: within one prior width of what they show (`shown`): not a patch
SHOWN_SHARE = 0.05
#: ... and is added instead of a better candidate the runs do not show when its gain is at
#: least this fraction of that candidate's (`preferred`)
SHOWN_TIE = 0.9
#: an effect parameter's prior width: a factor of 3 from its default on the log scale (a
#: quarter of its range for a linear one) is one σ ...
PLAUSIBLE = 3.0
#: ... and costs 5 % of the current model's systematic residual (e² - f²) on the e² scale
PRIOR_SHARE = 0.05
SELECTION = (f"an effect is added when, on the held-out last 40 % of every run and on the "
             f"scale where sensor noise and a systematic error add (the mean over runs and "
             f"channel groups of the squared NRMS error), its gain over the calibrated "
             f"current model, less the cost of its fitted parameters' distance from their "
             f"declared defaults (each parameter (ln(fitted/default) / ln {PLAUSIBLE:g})^2 "
             f"(ln of its own spread for one whose typical value varies over decades), "
             f"a linear one ((fitted - default) / a quarter of its range)^2, times "
             f"{PRIOR_SHARE:.0%} of the current model's systematic residual (error^2 - "
             f"floor^2): a value far outside its physical range must buy that with "
             f"evidence), (1) exceeds {Z_NOISE:g} standard "
             f"errors of what the held-out noise alone produces between the two predictions "
             f"(a likelihood-ratio test against the noise floor), (2) removes at least "
             f"{MIN_SHARE:.0%} of the current model's systematic residual (error^2 - "
             f"floor^2; {SHOWN_SHARE:.0%} for an effect the runs show by a check of their "
             f"own and whose fit lies within one prior width of what they show), (3) is at "
             f"least {NOISE_SHARE:.0%} of what the noise alone costs "
             "(floor^2): refitting the base and an effect to other noise moves a held-out "
             "error by less, and (4) is at least the squared resolution of the reduced model "
             "with the candidate in (the root-sum-square of the base's and each present "
             "effect's measured agreement with the virtual table beyond the base's: the most "
             "a patch of that model-form difference can remove); and its fit is sound: none "
             "of its own parameters within 1 % of a bound, correlated beyond 0.95 with a base "
             "parameter, or without influence on the data, and the effect acts within what "
             "the runs reach (a yield drift that no run reaches is not a yield). When the "
             "calibrated starting model leans on a bound of its declared values, the gain "
             "must also pass (1)-(4) "
             "over the starting model refitted with those bounds widened: an effect is not "
             "added where a wrong declaration explains as much. The best such candidate "
             f"(largest gain) is added, or one the runs show with at least {SHOWN_TIE:.0%} of "
             "its gain. After each addition every effect added earlier is "
             "tested the same way against the model without it (refitted) and removed when "
             "it no longer passes")


def implausibility(name: str, values: dict[str, float], table=None) -> list[tuple[str, float]]:
    """Each of effect `name`'s parameters in `values` (its units) as (what, z): z its
    distance from the default on `table` (a `vtable.effects.table.TableView`; None: the
    EERC table's) in prior widths (`PLAUSIBLE`)."""
    e, out = effect(name), []
    shown, where = getattr(table, "evidence", {}).get(name, ({}, ""))
    for q in e.params:
        if q.name not in values or q.discrete:  # a choice (which storey), not a distance
            continue
        v = float(values[q.name])
        d = q.default if table is None else q.default_on(table)
        source = q.source or "no source"
        if q.name in shown:  # what the runs themselves show (`Effect.evidence`)
            d, source = float(shown[q.name]), where
        u = "" if q.unit == "1" else f" {q.unit}"  # a ratio is printed bare
        if q.log and v > 0 and d > 0:
            z = math.log(v / d) / math.log(q.spread or PLAUSIBLE)
            what = (f"{q.name} {v:.3g}{u} is {max(v / d, d / v):.3g} x its "
                    f"{'shown value' if q.name in shown else 'default'} {d:.3g}{u}")
        else:
            z = (v - d) / (0.25 * (q.upper - q.lower))
            what = (f"{q.name} {v:.3g}{u} against its "
                    f"{'shown value' if q.name in shown else 'default'} {d:.3g}")
        out.append((f"{what} ({source})", z))
    return out


def prior_cost(g: Gain, model: Physics | None, name: str | None, table=None) -> float:
    """What candidate `name`'s fitted parameters in `model` cost on the e² scale: Σ z² ×
    `PRIOR_SHARE` × the current model's systematic residual (`implausibility`)."""
    if model is None or name is None or name not in model.effects:
        return 0.0
    z2 = sum(z * z for _, z in implausibility(name, model.effects[name], table))
    return z2 * PRIOR_SHARE * g.systematic


def shown(model: Physics | None, name: str | None, table) -> bool:
    """Whether effect `name` is one the runs show by a check of their own
    (`Effect.evidence`, in `table.evidence`) and `model`'s fit of it lies within one prior
    width of every value they show."""
    if model is None or name is None or not model.has(name):
        return False
    values, _ = getattr(table, "evidence", {}).get(name, ({}, ""))
    if not values:
        return False
    z = implausibility(name, {k: v for k, v in model.effects[name].items() if k in values},
                       table)
    return all(abs(v) <= 1.0 for _, v in z)


def preferred(passing: list) -> Any:
    """Of the candidates that pass, best first (`Candidate`s), the one to add: the best,
    unless it is not one the runs show (`shown`) and one that is gains at least
    `SHOWN_TIE` of its gain: an effect an independent check shows is preferred to one
    whose gain it nearly matches. None when none passes."""
    if not passing:
        return None
    best = passing[0]
    if shown(best.physics, best.effect, best.table) or best.gain is None:
        return best
    for c in passing[1:]:
        if c.gain is not None and shown(c.physics, c.effect, c.table) and \
                c.gain.gain >= SHOWN_TIE * best.gain.gain:
            return c
    return best


def preferred_note(best: Any, top: Any) -> str:
    """What the evidence of a candidate `preferred` to `top` says of it."""
    return (f"; added rather than {top.effect}: the runs show it, and its gain is "
            f"{best.gain.gain / top.gain.gain:.0%} of {top.effect}'s")


#: why an effect waits (time-invariant rounds first) or has had its turn (the last round
#: tries the effects that accumulate over a run, on the model the others made)
LATE = {False: "tried once the time-invariant effects are in (it accumulates over a run)",
        True: "this round tries what accumulates over a run (the others were tried before)"}


def failing(g: Gain | None, model: Physics | None = None, name: str | None = None,
            table=None, charged: bool = True) -> list[str]:
    """The statistical criteria of `SELECTION` a held-out gain does not meet (empty: it
    passes).

    Parameters
    ----------
    g
        The gain of the model with the candidate over the model without it.
    model
        The model with the candidate (its effects give the resolution, criterion 4; its
        fitted parameters the prior cost); None: the base's resolution, no prior.
    name
        The candidate effect.
    table
        The campaign's table (`vtable.effects.table.TableView`) the defaults are taken on;
        None: the EERC table's.
    charged
        Whether the gain is charged for the parameters' distance from their defaults
        (False: the criteria on the gain alone, `near_miss`).
    """
    if g is None:
        return ["no valid model"]
    cost = prior_cost(g, model, name, table) if charged else 0.0
    net = replace(g, e2_candidate=g.e2_candidate + cost)
    out = []
    if not net.z > Z_NOISE:
        out.append(f"its gain is {net.z_text} (needs {Z_NOISE:g})")
    share = SHOWN_SHARE if shown(model, name, table) else MIN_SHARE
    if not net.gain >= share * net.systematic:
        out.append(f"it removes {max(net.share, 0):.0%} of the systematic residual (needs "
                   f"{share:.0%}{' (what the runs show)' if share != MIN_SHARE else ''})")
    if not net.gain >= NOISE_SHARE * g.f2:
        out.append(f"its gain is {max(net.gain, 0) / g.f2:.0%} of what the noise alone costs "
                   f"(needs {NOISE_SHARE:.0%})" if g.f2 > 0 else "it gains nothing")
    r = resolution(() if model is None else model.effects)
    if not net.gain >= r * r:
        out.append(f"its gain ({math.sqrt(max(net.gain, 0)):.2%} on the NRMS scale) is below "
                   f"the resolution of the reduced model with it in ({r:.2%}: a patch of the "
                   "model-form difference could buy that)")
    if out and cost > 0:
        out[0] = "charged for its parameters' distance from their defaults, " + out[0]
        far = [w for w, z in implausibility(name, model.effects[name], table) if abs(z) > 1]
        whole = " (more than the whole gain)" if cost >= g.gain > 0 else ""
        out.append(f"its parameters' distance from their defaults costs {cost:.3g} of the "
                   f"gain {g.gain:.3g}{whole}" + (f" ({'; '.join(far)})" if far else ""))
    return out


def near_miss(c) -> bool:
    """Whether candidate `c` (a `result.Candidate`, fitted and refined) shows a held-out gain
    the selection's statistics take on their own — (1) above `Z_NOISE` standard errors of
    the noise, (2) at least `MIN_SHARE` of the systematic residual (`SHOWN_SHARE` for what
    the runs show), (3) at least `NOISE_SHARE` of the noise's cost, (4) at least the squared
    resolution of the model with it — before the cost of its parameters' distance from their
    defaults and the soundness of its fit: when it was not added, what stopped it is worth
    saying (`findings`). A current model within the noise (no systematic residual) leaves
    nothing to say."""
    g = c.gain
    if g is None or c.screened or c.not_fitted or c.unrefined or not g.systematic > 0:
        return False
    return not failing(g, c.physics, c.effect, c.table, charged=False)
