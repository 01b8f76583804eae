"""The discrete parameters of a fit: whole values an effect chooses among (which storeys
yield, `Param(discrete=True)`), each combination fitted and the cheapest kept.

An effect proposes its combinations (`Effect.choices`), and may propose more after seeing
the costs of those fitted (storey_yield grows the best run of yielding storeys). A fit's
continuous parameters start from a grid across their ranges (`TableModel`'s multistart);
a combination fitted before a better one was found had only that grid, and a threshold
law's grid can miss its valley (a sharp yield at the wrong drift): where a later proposal
wins, the first proposal that fitted best is fitted once more from the winner's continuous
values (`TableModel`'s `seed`, one more start; in a candidate's own fit, the `multistart`
effect choosing alone), so that the storey that yields alone is not lost to a run of
storeys that absorbed the misfit of its poor start.
"""

from __future__ import annotations

import copy
import dataclasses
import itertools

from vtable.effects.registry import get as effect
from vtable.errors import VtableError
from vtable.models.reduced import ReducedModel


def fit_choices(model, campaign, start, choices):
    """`model` (a `TableModel`) fitted once for every combination of the discrete
    parameters' whole values that the effects propose (`Effect.choices`) and the model can
    be built with, keeping the lowest training cost; `choice_costs_` holds each
    combination's (the lower of its two fits, for the one fitted again from a later
    winner's values).
    `choices`: (effect name, `Param`) of the discrete parameters chosen."""
    names = list(dict.fromkeys(n for n, _ in choices))

    def proposed(name: str, tried: list) -> list[dict]:
        own = [p for n, p in choices if n == name]
        allowed = effect(name).choices(start.specimen, tried)
        if allowed is None:  # every combination of the ranges, at once
            allowed = [] if tried else [
                dict(zip([p.name for p in own], vs, strict=True))
                for vs in itertools.product(*(range(int(p.lower), int(p.upper) + 1)
                                              for p in own))]
        return [{(name, k): v for k, v in a.items()} for a in allowed]

    def fitted(combo: dict, seed: dict | None = None):
        ph = start
        for (name, pname), v in combo.items():
            ph = dataclasses.replace(ph, effects={**ph.effects,
                                                  name: {**ph.effects[name], pname: v}})
        try:
            ReducedModel(ph, model.vt, kernels=False)
        except VtableError:  # e.g. a storey the specimen does not have
            return None
        sub = copy.copy(model)
        sub.clear_caches()
        if seed is not None:
            sub.seed = seed
        sub._fit_from(campaign, ph)
        return sub

    batch: list[dict] = [{}]
    for name in names:
        batch = [{**c, **a} for c in batch for a in proposed(name, [])]
    first = list(batch)
    best, best_key, costs, seen, tried = None, None, {}, set(), []
    while batch:
        for combo in batch:
            key = tuple(combo.values())
            seen.add(key)
            sub = fitted(combo)
            if sub is None:
                continue
            costs[key] = sub.cost_
            tried.append(({k: v for (_, k), v in combo.items()}, sub.cost_))
            if best is None or sub.cost_ < best.cost_:
                best, best_key = sub, key
        if len(names) != 1:  # several effects choosing: their first proposals only
            break
        batch = [c for c in proposed(names[0], tried) if tuple(c.values()) not in seen]
    if best is None:
        raise VtableError(f"no value of {', '.join(f'{n}.{p.name}' for n, p in choices)} "
                          "gives a model of these runs")
    name = names[0]
    firsts = [c for c in first if tuple(c.values()) in costs]
    if len(names) == 1 and model.multistart == name and firsts and best.physics_ is not None \
            and best_key not in {tuple(c.values()) for c in first}:
        # the first proposal that fitted best, again from the winner's continuous values
        combo = min(firsts, key=lambda c: costs[tuple(c.values())])
        sub = fitted(combo, dict(best.physics_.effects[name]))
        if sub is not None and sub.cost_ < costs[tuple(combo.values())]:
            costs[tuple(combo.values())] = sub.cost_
            if sub.cost_ < best.cost_:
                best = sub
    seed = model.seed
    model.__dict__.update(best.__dict__)
    model.seed, model.choice_costs_ = seed, costs
    return model
