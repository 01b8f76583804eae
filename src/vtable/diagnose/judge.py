"""A fit judged as a candidate of the diagnosis: its held-out error and its gain over the
current model (`statistics.held_out_gain`, what `SELECTION` reads), or the reason it has
none (no valid model; kept from being fitted by the screen); whether `SELECTION` would add
it (`admissible`), and the round's choice (`select`)."""

from __future__ import annotations

from typing import Any

from vtable.diagnose.campaign import Campaign
from vtable.diagnose.compare import compare
from vtable.diagnose.result import Candidate, evidence
from vtable.diagnose.selection import failing, preferred, preferred_note
from vtable.diagnose.statistics import Comparison, held_out_gain
from vtable.diagnose.workers import CandidateFit
from vtable.effects.registry import get as effect
from vtable.models.physics import Physics


def judged(name: str, fit: CandidateFit, current: dict, campaign: Campaign, floor: float,
           table: Any, unrefined: str = "") -> Candidate:
    """The candidate `name` that `fit` makes, scored on the held-out segments against the
    current model's predictions `current`; `table` the campaign's `TableView`."""
    ph, pred = fit.physics, fit.predictions
    values, n = dict(ph.effects[name]), len(effect(name).params)
    if isinstance(pred, Exception):  # the fit found no model it could build
        return Candidate(name, values, float("inf"), fit.train_error, "", n, ph,
                         [f"no valid model found: {pred}"], None)
    err = compare(pred, campaign.runs, scored="held", floor=floor).error
    gain = held_out_gain(current, pred, campaign.runs, campaign.noise)
    return Candidate(name, values, err, fit.train_error, "", n, ph, fit.flags, pred,
                     fit.screened, fit.cost, gain, table, unrefined=unrefined)


def not_fitted(name: str, ph: Physics, cost: float, err: float, current: dict,
               campaign: Campaign, table: Any, why: str) -> Candidate:
    """A candidate the screen keeps from being fitted: at its defaults (`ph`), credited
    with the current model's predictions and error `err` (no gain claimed), screened."""
    gain = held_out_gain(current, current, campaign.runs, campaign.noise)
    return Candidate(name, dict(ph.effects[name]), err, float("nan"), "",
                     len(effect(name).params), ph, [], current, True, cost, gain, table,
                     not_fitted=why)


def admissible(diag, c: Candidate, widened: tuple | None) -> bool:
    """Whether SELECTION would add `c` in the diagnosis `diag` (a `Diagnoser`): its gain
    passes the statistical criteria, its fit is sound, and (when the starting model leans
    on its bounds, `widened`) it beats the starting model refitted with them widened too
    (sets `c.stand_in`)."""
    if widened is not None and c.predictions is not None:
        c.stand_in = failing(held_out_gain(widened[2], c.predictions, diag.runs,
                                           diag.campaign.noise),
                             c.physics, c.effect, diag.table_view)
    return not c.failing() and not c.blocking and not c.stand_in


def select(diag, ranking: list[Candidate], widened: tuple | None, err: float,
           cmp_cur: Comparison) -> Candidate | None:
    """SELECTION: of the candidates whose held-out gain passes the statistical criteria
    and whose fit is sound (`admissible`), the preferred one (`selection.preferred`), or
    None; every candidate's evidence written, only the chosen one's predictions kept."""
    passing = [c for c in ranking if admissible(diag, c, widened)]
    best = preferred(passing)
    for c in ranking:
        c.evidence = evidence(c, err, diag.floor, cmp_cur)
        if c is not best:
            c.predictions = None
    if best is not None and best is not passing[0]:
        best.evidence += preferred_note(best, passing[0])
    return best
