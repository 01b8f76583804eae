"""A fit judged as a candidate of the diagnosis: its held-out error and its gain over the
current model (`statistics.held_out_gain`, what `SELECTION` reads), or the reason it has
none (no valid model; kept from being fitted by the screen)."""

from __future__ import annotations

from typing import Any

from vtable.diagnose.campaign import Campaign
from vtable.diagnose.compare import compare
from vtable.diagnose.result import Candidate
from vtable.diagnose.statistics import held_out_gain
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
