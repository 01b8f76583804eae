"""What a campaign's runs show of the catalog effects' parameters before any fit
(`Effect.evidence`: identification, the checks on the runs): the diagnosis starts each
candidate's fit there too (`engine`) and centres its prior there (`selection.implausibility`
reads `TableView.evidence`); a model given its effects by name (`vtable compare --with`,
`vtable drive --with`, `diagnose --with`) starts them there (`started`)."""

from __future__ import annotations

import dataclasses

from vtable.diagnose.prose import params_text
from vtable.display import run_family
from vtable.effects.registry import get as effect
from vtable.effects.table import TableView
from vtable.models.physics import Physics

#: what a diagnosis does with what the runs show of an effect (`shown_by_runs`): a
#: candidate's, and an effect's a model is given
CHARGED = ("its fit starts there and is charged for its distance from these, not from its "
           "defaults")
STARTS = "its fit starts there"


def shown_by_runs(catalog, campaign, notes: list[str], use: str = CHARGED
                  ) -> dict[str, tuple[dict, str]]:
    """What the campaign's runs show of each catalog effect's parameters
    (`Effect.evidence`), each said in `notes` with what is done with it (`use`): effect ->
    (values, where from)."""
    out = {}
    for name in catalog:
        e = effect(name)
        if e.unsupported(campaign):  # not tried: the runs show none of it
            continue
        ev = e.evidence(campaign)
        if ev:  # held within the parameters' bounds (a fit never leaves them)
            ev = ({k: min(max(float(v), e.param(k).lower), e.param(k).upper)
                   for k, v in ev[0].items()}, ev[1])
            out[name] = ev
            vals = params_text(name, ev[0], run_family(campaign.runs[0]), ".3g")
            notes.append(f"{name}: the runs show {vals} ({ev[1]}): {use}")
    return out


def started(start: Physics, effects, campaign, notes: list[str]) -> Physics:
    """`start` with each of `effects` it does not hold added at what the runs show of its
    parameters (`shown_by_runs`, said in `notes`), else at its defaults: a model given its
    effects by name (`vtable compare --with`) starts where the diagnosis starts them."""
    new = [e for e in effects if not start.has(e)]
    shown = shown_by_runs(new, campaign, notes, STARTS) if new else {}
    for e in new:
        start = start.with_effect(e, dict(shown[e][0]) if e in shown else None)
    return start


def evidence_view(vt, catalog, campaign, notes: list[str]) -> TableView:
    """The view of table `vt` the diagnosis takes the effects' defaults and priors on,
    with what the runs show of each of `catalog` (`shown_by_runs`)."""
    return dataclasses.replace(TableView.of(vt),
                               evidence=shown_by_runs(catalog, campaign, notes))
