"""The diagnosis loop: for every catalog effect the model lacks, add it, fit its
parameters together with the base loop (f_o, ξ_o, k_o) and the effects already in the
model on the training segments of the campaign, score on the held-out segments, rank by
held-out error plus a parsimony penalty, add the best if it improves the model beyond the
noise, repeat.

Training = the first 60 % of every run, held out = the last 40 % (`compare.segments`).
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize

from vtable.diagnose.compare import (
    GROUPS,
    Comparison,
    compare,
    group_prediction,
    group_signal,
    localisation_text,
    noise_floor,
    segments,
)
from vtable.effects.catalog import CATALOG, effect
from vtable.effects.physics import Physics, nominal_open_loop
from vtable.effects.reduced import ReducedModel
from vtable.errors import VtableError
from vtable.params.loops import OpenLoop
from vtable.params.virtual import virtual_table
from vtable.runs.model import Run

PENALTY = 0.002  # held-out error charged per added parameter
WORKERS = min(2, os.cpu_count() or 1)
MIN_GAIN = 0.10  # an effect must remove 10 % of the excess over the noise floor ...
FLOOR_GAIN = 0.2  # ... and at least 0.2 x the noise floor
REQUIRED = ("h_span",)


@dataclass
class Candidate:
    effect: str
    params: dict[str, float]
    error_after: float
    train_error: float
    evidence: str
    n_params: int
    physics: Physics = field(repr=False)

    @property
    def score(self) -> float:
        return self.error_after + PENALTY * self.n_params


@dataclass
class Round:
    ranking: list[Candidate]
    added: str | None
    error: float
    before: float


@dataclass
class Diagnosis:
    start_effects: list[str]
    start_error: float
    noise_floor: float
    rounds: list[Round]
    final: Physics
    final_error: float
    verdict: str
    comparison_start: Comparison | None = None
    comparison_final: Comparison | None = None

    @property
    def final_effects(self) -> list[str]:
        return list(self.final.effects)

    def history(self) -> list[tuple[str, float]]:
        h = [("start", self.start_error)]
        h += [(r.added, r.error) for r in self.rounds if r.added]
        return h

    def to_json(self) -> dict[str, Any]:
        """The keys of shared/spec/effects.md (and more)."""
        return {
            "format": "vtable-diagnosis/1",
            "start_effects": self.start_effects,
            "start_error": self.start_error,
            "noise_floor": self.noise_floor,
            "rounds": [{"ranking": [{"effect": c.effect, "error_after": c.error_after,
                                     "train_error": c.train_error, "params": c.params,
                                     "n_params": c.n_params, "evidence": c.evidence}
                                    for c in r.ranking],
                        "added": r.added, "error": r.error, "error_before": r.before}
                       for r in self.rounds],
            "final_effects": self.final_effects,
            "final_params": {k: v for k, v in self.final.effects.items()},
            "final_base": {"f_o_hz": self.final.open_loop.f_o, "xi_o": self.final.open_loop.xi_o,
                           "k_o_per_s": self.final.open_loop.k_o},
            "final_error": self.final_error,
            "verdict": self.verdict,
            "error_definition": "mean over runs and channel groups of the normalised RMS "
                                "error ||model - measured|| / ||measured|| on the held-out "
                                "last 40 % of every run",
        }


def check_campaign(runs: Sequence[Run]) -> None:
    """Clear messages for what a diagnosis cannot use."""
    if not runs:
        raise VtableError("diagnosis needs at least one run")
    ref = runs[0].configuration()
    for r in runs:
        for c in REQUIRED:
            if not r.has(c):
                raise VtableError(f"{r.name}: channel {c!r} (the command) is missing; the "
                                  "model is driven by it")
            if r.missing.get(c):
                raise VtableError(f"{r.name}: channel {c!r} has {r.missing[c]} missing samples")
        if r.configuration() != ref:
            raise VtableError(f"{r.name}: a different configuration ([table], [control] or "
                              f"[specimen]) from {runs[0].name}; diagnose one configuration")
        if "specimen" not in r.meta:
            raise VtableError(f"{r.name}: no [specimen] table; the model needs the specimen")
        if len(r.time) < 512:
            raise VtableError(f"{r.name}: {len(r.time)} samples ({r.duration:.2f} s) is shorter "
                              "than one 512-sample analysis frame")
        if not any(group_signal(r, g) is not None for g in GROUPS if g != "pitch"):
            raise VtableError(f"{r.name}: none of the response channels the model predicts "
                              f"({', '.join(c for g in GROUPS.values() for c in g)})")


class Diagnoser:
    """fit/score on a campaign; `diagnose()` runs the loop."""

    def __init__(self, runs: Sequence[Run], start_effects: Sequence[str] = (),
                 catalog: Sequence[str] | None = None,
                 progress: Callable[[int, int, str], None] | None = None,
                 max_rounds: int = 4) -> None:
        check_campaign(runs)
        for e in start_effects:
            effect(e)
        self.runs = list(runs)
        self.vt = virtual_table()
        self.specimen = self.runs[0].specimen()
        self.start = Physics(nominal_open_loop(self.vt), self.specimen,
                             {e: {} for e in start_effects})
        self.catalog = list(catalog or CATALOG)
        for e in self.catalog:
            effect(e)
        self.progress = progress or (lambda i, n, s: None)
        self.max_rounds = max_rounds
        self.floor = noise_floor(self.runs)
        self._targets = []
        for r in self.runs:
            tr, _ = segments(r)
            for g in GROUPS:
                y = group_signal(r, g)
                if y is not None:
                    self._targets.append((r, g, y[tr][::2], float(np.linalg.norm(y[tr][::2]))))

    # -- parameter vector --------------------------------------------------------------
    def _layout(self, ph: Physics) -> list[tuple[str, str, float, float, bool]]:
        lay = [("base", "f_o", 1.0, 100.0, True), ("base", "xi_o", 0.02, 5.0, True),
               ("base", "k_o", 1.0, 500.0, True)]
        for name in ph.effects:
            for p in CATALOG[name].params:
                lay.append((name, p.name, p.lower, p.upper, p.log))
        return lay

    def _pack(self, ph: Physics, lay) -> np.ndarray:
        x = []
        for owner, name, _, _, log in lay:
            v = getattr(ph.open_loop, name) if owner == "base" else ph.effects[owner][name]
            x.append(math.log(v) if log else v)
        return np.array(x)

    def _unpack(self, x: np.ndarray, ph: Physics, lay) -> Physics:
        base = {}
        eff = {k: dict(v) for k, v in ph.effects.items()}
        for xi, (owner, name, lo, hi, log) in zip(x, lay, strict=True):
            v = float(np.clip(math.exp(xi) if log else xi, lo, hi))
            if owner == "base":
                base[name] = v
            else:
                eff[owner][name] = v
        return dataclasses.replace(ph, open_loop=OpenLoop(**base), effects=eff)

    # -- simulate, fit, score ----------------------------------------------------------
    def predict(self, ph: Physics, train_only: bool = False) -> dict[str, dict[str, np.ndarray]]:
        model = ReducedModel(ph, self.vt)
        out = {}
        for r in self.runs:
            n = segments(r)[0].stop if train_only else len(r.time)
            out[r.name] = model.simulate(r.time[:n], r.channel("h_span")[:n])
        return out

    def _residuals(self, ph: Physics) -> np.ndarray:
        try:
            pred = self.predict(ph, train_only=True)
        except VtableError:
            return np.full(sum(len(t[2]) for t in self._targets), 10.0)
        res = []
        for r, g, y, norm in self._targets:
            yhat = group_prediction(pred[r.name], r, g)[: segments(r)[0].stop][::2]
            e = (yhat - y) / norm
            res.append(np.where(np.isfinite(e), e, 10.0 / math.sqrt(len(e))))
        return np.concatenate(res)

    def fit(self, ph: Physics, multistart: str | None = None) -> tuple[Physics, float]:
        """Least-squares fit of base + effect parameters on the training segments; for the
        effect `multistart`, its parameters start from the best of a few trial values."""
        lay = self._layout(ph)
        x0 = self._pack(ph, lay)
        if multistart:
            # trial starts for the new effect's parameters, with the current base loop and
            # with the nominal one (the current base may have compensated for the effect)
            idx = [i for i, (o, *_rest) in enumerate(lay) if o == multistart]
            nominal = self._pack(dataclasses.replace(ph, open_loop=self.start.open_loop), lay)
            best, best_x = np.inf, x0
            for base in (x0[:3], nominal[:3]):
                for frac in (0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95, None):
                    x = x0.copy()
                    x[:3] = base
                    for i in idx:
                        _, _, lo, hi, log = lay[i]
                        if frac is not None:
                            a, b = (math.log(lo), math.log(hi)) if log else (lo, hi)
                            x[i] = a + frac * (b - a)
                    c = float(np.sum(self._residuals(self._unpack(x, ph, lay)) ** 2))
                    if c < best:
                        best, best_x = c, x
            x0 = best_x
        lo = np.array([math.log(a) if log else a for _, _, a, _, log in lay])
        hi = np.array([math.log(b) if log else b for _, _, _, b, log in lay])
        x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
        sol = scipy.optimize.least_squares(lambda x: self._residuals(self._unpack(x, ph, lay)),
                                           x0, bounds=(lo, hi), diff_step=1e-4, xtol=1e-6,
                                           ftol=1e-8, max_nfev=40)
        fitted = self._unpack(sol.x, ph, lay)
        return fitted, float(np.sqrt(np.mean(sol.fun**2) * len(sol.fun) / len(self._targets)))

    def score(self, ph: Physics, detail: bool = False) -> Comparison:
        return compare(self.predict(ph), self.runs, scored="held", floor=self.floor,
                       detail=detail)

    # -- the loop ------------------------------------------------------------------------
    def diagnose(self) -> Diagnosis:
        steps = 1 + self.max_rounds * len(self.catalog)
        done = 0
        self.progress(done, steps, "fitting the starting model")
        current, _ = self.fit(self.start)
        self.start_fitted = current
        done += 1
        cmp0 = self.score(current, detail=True)
        err = cmp0.error
        start_err = err
        rounds: list[Round] = []
        verdict = ""
        for _ in range(self.max_rounds):
            todo = [e for e in self.catalog if not current.has(e)]
            if not todo:
                verdict = "every catalog effect is in the model"
                break
            cmp_cur = self.score(current, detail=True)
            ranking = []

            def trial(name: str, base: Physics = current) -> Candidate:
                cand, train = self.fit(base.with_effect(name), multistart=name)
                return Candidate(name, dict(cand.effects[name]), self.score(cand).error, train,
                                 "", len(CATALOG[name].params), cand)

            # candidates are independent: fit them on both cores (the kernel releases the GIL)
            with ThreadPoolExecutor(max_workers=WORKERS) as pool:
                futures = {pool.submit(trial, name): name for name in todo}
                for fut in as_completed(futures):
                    ranking.append(fut.result())
                    done += 1
                    self.progress(done, steps, f"tried {futures[fut]}")
            ranking.sort(key=lambda c: c.score)
            for c in ranking:
                c.evidence = _evidence(c, err, self.floor, cmp_cur)
            best = ranking[0]
            gain = err - best.error_after
            needed = max(MIN_GAIN * (err - self.floor), FLOOR_GAIN * self.floor,
                         PENALTY * best.n_params)
            if gain > needed:
                rounds.append(Round(ranking, best.effect, best.error_after, err))
                current, err = best.physics, best.error_after
            else:
                rounds.append(Round(ranking, None, err, err))
                verdict = (f"no missing effect: the best candidate ({best.effect}) would lower "
                           f"the held-out error by {gain:.2%}, less than the {needed:.2%} the "
                           f"noise floor ({self.floor:.1%}) and the parsimony penalty require")
                break
        self.progress(steps, steps, "done")
        added = [r.added for r in rounds if r.added]
        if not verdict:
            verdict = f"stopped after {self.max_rounds} rounds"
        if added:
            verdict = (f"added {', '.join(added)}: held-out error {start_err:.2%} -> {err:.2%} "
                       f"(noise floor {self.floor:.2%}); " + verdict)
        elif not verdict.startswith("no missing effect"):
            verdict = "no missing effect; " + verdict
        return Diagnosis(list(self.start.effects), start_err, self.floor, rounds, current, err,
                         verdict, cmp0, self.score(current, detail=True))


def _evidence(c: Candidate, err: float, floor: float, cmp: Comparison) -> str:
    worst = cmp.worst_groups(2)
    where = ", ".join(g for g, _ in worst)
    band = cmp.worst_band(worst[0][0]) if worst else None
    removed = (err - c.error_after) / max(err - floor, 1e-12)
    params = ", ".join(f"{k} = {v:.3g} {p.unit}" for (k, v), p in
                       zip(c.params.items(), CATALOG[c.effect].params, strict=True))
    return (f"residual concentrated in {where}" + (f" at {band[0]}" if band else "")
            + f"; adding {c.effect} removes {removed:.0%} of it (held-out error {err:.2%} -> "
              f"{c.error_after:.2%}); fitted {params}")


def diagnose(runs: Sequence[Run], start_effects: Sequence[str] = (), **kw) -> Diagnosis:
    return Diagnoser(runs, start_effects, **kw).diagnose()


def localise(d: Diagnosis) -> str:
    return localisation_text(d.comparison_start) if d.comparison_start else ""
