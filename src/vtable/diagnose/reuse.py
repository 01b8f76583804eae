"""A fitted model's values reused, not fitted again: `TableModel.at` (`vtable drive
--from` takes a diagnosis's final model this way)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from vtable.diagnose.campaign import Campaign
from vtable.diagnose.layout import with_states
from vtable.effects.registry import get as effect
from vtable.errors import VtableError
from vtable.models.physics import Physics, nominal_open_loop


def model_at(m, campaign: Campaign, values: Mapping[str, float], source: str = "values"):
    """The model at given values of every calibrated parameter, not fitted: a
    diagnosis's (`vtable drive --from`). `values`: "owner.param" -> value in the
    parameter's unit, the base's keys (`base_table`) and each effect's
    "effect.param"; a key missing or unknown to this campaign's model, or a value
    outside its bounds, is an error naming `source` and the key. Sets `physics_`,
    `base_`, `flags_` (values at a bound) and `notes_`, as `fit` does."""
    m.campaign_, m.vt, m.declared = campaign, campaign.table, campaign.specimen
    m.state_specimens = campaign.state_specimens
    start = with_states(m.start or Physics(nominal_open_loop(m.vt), campaign.specimen, {}),
                        campaign)
    for e in m.effects:
        if not start.has(e):
            start = start.with_effect(e)
    values = dict(values)
    for name in list(start.effects):
        for p in effect(name).params:
            key = f"{name}.{p.name}"
            if p.discrete and key in values:
                start = dataclasses.replace(start, effects={
                    **start.effects, name: {**start.effects[name],
                                            p.name: float(values.pop(key))}})
    lay = m._layout(start)
    keys = [p.key for p in lay]
    unknown = sorted(set(values) - set(keys))
    missing = [k for k in keys if k not in values]
    states = [k for k in unknown if k.startswith("specimen[")]
    if states:
        raise VtableError(f"{source}: {states[0]!r}: the model was fitted on runs of several "
                          "specimen states; give runs of those states ([specimen] state) to "
                          "reuse it")
    if unknown or missing:
        raise VtableError(f"{source}: " + (f"{unknown[0]!r} is not a parameter of the "
                                           "model of these runs" if unknown else
                                           f"no value for {missing[0]!r}")
                          + " (was it made on these runs, with these effects?)")
    ph = start
    for p in lay:
        v = float(values[p.key])
        tol = 1e-6 * (p.upper - p.lower)
        if not p.lower - tol <= v <= p.upper + tol:
            raise VtableError(f"{source}: {p.key} = {v:g} is outside its bounds "
                              f"[{p.lower:g}, {p.upper:g}] for these runs' declarations")
        ph = p.set(ph, min(max(v, p.lower), p.upper))
    m.start_, m.layout_, m.physics_ = start, lay, ph
    m.base_ = m.base_table(ph)
    m.flags_ = m.at_bounds(ph)
    m.notes_ = list(campaign.notes)
    return m
