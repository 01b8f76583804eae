"""What a campaign's runs show of the catalog effects' parameters before any fit
(`Effect.evidence`: identification, the checks on the runs): the diagnosis starts each
candidate's fit there too (`engine`) and centres its prior there (`selection.implausibility`
reads `TableView.evidence`)."""

from __future__ import annotations

import dataclasses

from vtable.effects.registry import get as effect
from vtable.effects.table import TableView


def shown_by_runs(catalog, campaign, notes: list[str]) -> dict[str, tuple[dict, str]]:
    """What the campaign's runs show of each catalog effect's parameters
    (`Effect.evidence`), each said in `notes`: effect -> (values, where from)."""
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
            vals = ", ".join(f"{k} {v:.3g}" for k, v in ev[0].items())
            notes.append(f"{name}: the runs show {vals} ({ev[1]}): its fit starts there and "
                         "is charged for its distance from these, not from its defaults")
    return out


def evidence_view(vt, catalog, campaign, notes: list[str]) -> TableView:
    """The view of table `vt` the diagnosis takes the effects' defaults and priors on,
    with what the runs show of each of `catalog` (`shown_by_runs`)."""
    return dataclasses.replace(TableView.of(vt),
                               evidence=shown_by_runs(catalog, campaign, notes))
