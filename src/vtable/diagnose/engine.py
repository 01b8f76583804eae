"""The diagnosis loop: for every catalog effect the model lacks, add it, fit its
parameters together with the base loop (f_o, ξ_o, k_o) and the effects already in the
model on the training segments of the campaign, score on the held-out segments, rank by
held-out error plus a parsimony penalty, add the best if it improves the model beyond the
noise, repeat.

Training = the first 60 % of every run, held out = the last 40 % (`compare.segments`), both
at the analysis rate (`compare.analysis_run`: runs faster than 200 Hz are anti-alias
filtered and resampled to 200 Hz; slower ones keep their rate).

The verdict is honest about what is left: the final model's held-out error is compared
with the noise floor by `compare.UNEXPLAINED_RULE` (consistent when err ≤ 2 × floor: noise and
a systematic error add in quadrature, err² ≈ floor² + sys²). Above that, `unexplained`
gives the ratio and where the residual lives, and the verdict says a residual remains
unexplained; "no missing effect" is said only when the final error is consistent with the
noise. A candidate whose fitted parameters sit within 1 % of a bound (on the fitted scale:
logarithmic for log parameters) is flagged: the fit may have pushed the effect where it is
not physics but a patch.

Ctrl-C: the loop runs in a worker thread; the caller's thread only waits and reports
progress. An interrupt sets a stop flag that the residual function checks between
simulations, pending candidate fits are cancelled, and `DiagnosisInterrupted` (a
KeyboardInterrupt) carries the rounds finished.
"""

from __future__ import annotations

import dataclasses
import math
import os
import queue
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize

from vtable.diagnose.compare import (
    GROUPS,
    NOISE_FACTOR,
    UNEXPLAINED_RULE,
    Comparison,
    analysis_run,
    campaign_notes,
    compare,
    group_prediction,
    group_signal,
    localisation_text,
    noise_floor,
    segments,
    unexplained,
)
from vtable.effects.physics import Physics, nominal_open_loop
from vtable.effects.reduced import ReducedModel
from vtable.effects.registry import get as effect
from vtable.effects.registry import names as registered
from vtable.errors import VtableError
from vtable.params.loops import OpenLoop
from vtable.params.virtual import virtual_table
from vtable.runs.model import Run

PENALTY = 0.002  # held-out error charged per added parameter
WORKERS = min(2, os.cpu_count() or 1)
MIN_GAIN = 0.10  # an effect must remove 10 % of the excess over the noise floor ...
FLOOR_GAIN = 0.2  # ... and at least 0.2 x the noise floor
REQUIRED = ("h_span",)
AT_BOUND = 0.01  # a fitted value within 1 % of its range (fitted scale) of a bound is flagged
#: the base loop's fitted parameters: name -> (JSON key "owner.param", unit, lower, upper)
BASE_PARAMS = {"f_o": ("servo_loop.f_o_hz", "Hz", 1.0, 100.0),
               "xi_o": ("servo_loop.xi_o", "1", 0.02, 5.0),
               "k_o": ("servo_loop.k_o_per_s", "1/s", 1.0, 500.0)}
ERROR_DEFINITION = ("mean over runs and channel groups of the normalised RMS error "
                    "||model - measured|| / ||measured|| on the held-out last 40 % of every "
                    "run, at the analysis rate (runs faster than 200 Hz anti-alias filtered and "
                    "resampled to 200 Hz); the noise floor is the same measure for the sensor "
                    "noise alone")


class _StopRequestedError(Exception):
    """Raised inside a fit when the diagnosis is being interrupted."""


@dataclass
class Candidate:
    effect: str
    params: dict[str, float]
    error_after: float
    train_error: float
    evidence: str
    n_params: int
    physics: Physics = field(repr=False)
    flags: list[str] = field(default_factory=list)

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
    start_error: float | None
    noise_floor: float
    rounds: list[Round]
    final: Physics
    final_error: float | None
    verdict: str
    comparison_start: Comparison | None = None
    comparison_final: Comparison | None = None
    base: dict[str, dict[str, Any]] = field(default_factory=dict)
    unexplained: dict[str, Any] | None = None
    notes: list[str] = field(default_factory=list)
    interrupted: bool = False

    @property
    def final_effects(self) -> list[str]:
        return list(self.final.effects)

    def history(self) -> list[tuple[str, float]]:
        if self.start_error is None:
            return []
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
            "base": self.base,
            "rounds": [{"ranking": [{"effect": c.effect, "error_after": c.error_after,
                                     "train_error": c.train_error, "params": c.params,
                                     "n_params": c.n_params, "evidence": c.evidence,
                                     "flags": c.flags}
                                    for c in r.ranking],
                        "added": r.added, "error": r.error, "error_before": r.before}
                       for r in self.rounds],
            "final_effects": self.final_effects,
            "final_params": {k: v for k, v in self.final.effects.items()},
            "final_base": {"f_o_hz": self.final.open_loop.f_o, "xi_o": self.final.open_loop.xi_o,
                           "k_o_per_s": self.final.open_loop.k_o},
            "final_error": self.final_error,
            "unexplained": self.unexplained,
            "verdict": self.verdict,
            "interrupted": self.interrupted,
            "notes": self.notes,
            "error_definition": ERROR_DEFINITION,
            "unexplained_rule": UNEXPLAINED_RULE,
        }


class DiagnosisInterrupted(KeyboardInterrupt):
    """Ctrl-C during `Diagnoser.diagnose`: `partial` is the diagnosis of the rounds that
    finished (`interrupted` True)."""

    def __init__(self, partial: Diagnosis) -> None:
        super().__init__(partial.verdict)
        self.partial = partial


def check_campaign(runs: Sequence[Run]) -> list[Run]:
    """Clear messages for what a diagnosis cannot use; returns the runs at their analysis
    rate (`compare.analysis_run`)."""
    if not runs:
        raise VtableError("diagnosis needs at least one run")
    ref = runs[0].configuration()
    out = []
    for r in runs:
        for c in REQUIRED:
            if not r.has(c):
                raise VtableError(f"{r.name}: channel {c!r} (the command) is missing; the "
                                  "model is driven by it")
            if r.missing.get(c):
                raise VtableError(f"{r.name}: channel {c!r} has {r.missing[c]} missing samples")
        x = r.channels["h_span"]
        if not np.all(np.isfinite(x)):
            raise VtableError(f"{r.name}: channel 'h_span' has non-finite samples")
        if np.ptp(x) == 0:
            raise VtableError(f"{r.name}: channel 'h_span' (the command) is "
                              + ("zero throughout" if not np.any(x) else f"constant ({x[0]:g} m)")
                              + "; a model driven by it predicts no motion to compare")
        if r.configuration() != ref:
            raise VtableError(f"{r.name}: a different configuration ([table], [control] or "
                              f"[specimen]) from {runs[0].name}; diagnose one configuration")
        if "specimen" not in r.meta:
            raise VtableError(f"{r.name}: no [specimen] table; the model needs the specimen")
        a = analysis_run(r)
        if len(a.time) < 512:
            raise VtableError(f"{r.name}: {len(a.time)} samples ({r.duration:.2f} s) at "
                              f"{a.fs:.4g} Hz is shorter than one 512-sample analysis frame")
        if not any(group_signal(a, g) is not None for g in GROUPS if g != "pitch"):
            raise VtableError(f"{r.name}: none of the response channels the model predicts "
                              f"({', '.join(c for g in GROUPS.values() for c in g)})")
        out.append(a)
    return out


@dataclass
class _State:
    """What the loop has established so far (read by the caller on an interrupt)."""

    current: Physics | None = None
    err: float | None = None
    start_err: float | None = None
    cmp0: Comparison | None = None
    cmp: Comparison | None = None  # detailed comparison of `current`, when made
    rounds: list[Round] = field(default_factory=list)
    result: Diagnosis | None = None
    error: BaseException | None = None


class Diagnoser:
    """fit/score on a campaign; `diagnose()` runs the loop.

    `runs` are the campaign as read; `self.runs` the same at the analysis rate, and
    `self.notes` what the readers reported, the resampling done and the channels left out.
    """

    def __init__(self, runs: Sequence[Run], start_effects: Sequence[str] = (),
                 catalog: Sequence[str] | None = None,
                 progress: Callable[[int, int, str], None] | None = None,
                 max_rounds: int = 4) -> None:
        self.source_runs = list(runs)
        self.runs = check_campaign(runs)
        for e in start_effects:
            effect(e)
        self.notes = campaign_notes(self.runs)
        self.vt = virtual_table()
        self.specimen = self.runs[0].specimen()
        self.start = Physics(nominal_open_loop(self.vt), self.specimen,
                             {e: {} for e in start_effects})
        self.catalog = list(catalog or registered())
        for e in self.catalog:
            effect(e)
        self.progress = progress or (lambda i, n, s: None)
        self.max_rounds = max_rounds
        self.floor = noise_floor(self.runs)
        self._stop = threading.Event()
        self._targets = []
        for r in self.runs:
            tr, _ = segments(r)
            for g in GROUPS:
                y = group_signal(r, g)
                if y is not None:
                    self._targets.append((r, g, y[tr][::2], float(np.linalg.norm(y[tr][::2]))))

    # -- parameter vector --------------------------------------------------------------
    def _layout(self, ph: Physics) -> list[tuple[str, str, float, float, bool]]:
        lay = [("base", n, lo, hi, True) for n, (_, _, lo, hi) in BASE_PARAMS.items()]
        for name in ph.effects:
            for p in effect(name).params:
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

    def at_bounds(self, ph: Physics) -> list[str]:
        """The fitted parameters of `ph` within 1 % of a bound, on the fitted scale (the
        logarithm for log parameters): 'owner.param at its lower bound (value unit)'."""
        flags = []
        for owner, name, lo, hi, log in self._layout(ph):
            v = getattr(ph.open_loop, name) if owner == "base" else ph.effects[owner][name]
            if owner == "base":
                key, unit = BASE_PARAMS[name][:2]
            else:
                key = f"{owner}.{name}"
                unit = next(p.unit for p in effect(owner).params if p.name == name)
            f = (lambda z: math.log(z)) if log else (lambda z: z)
            pos = (f(v) - f(lo)) / (f(hi) - f(lo))
            for side, bound, near in (("lower", lo, pos <= AT_BOUND),
                                      ("upper", hi, pos >= 1 - AT_BOUND)):
                if near:
                    u = "" if unit == "1" else f" {unit}"
                    flags.append(f"{key} at its {side} bound ({v:.4g}{u}; bound {bound:g}{u})")
        return flags

    def base_table(self, ph: Physics) -> dict[str, dict[str, Any]]:
        """The spec's `base`: every calibrated base parameter, "owner.param" ->
        {declared, fitted, bounds, unit}. Declared = the table preset's nominal loop (Table
        B.5 through eq 6.16)."""
        return {key: {"declared": getattr(self.start.open_loop, n),
                      "fitted": getattr(ph.open_loop, n), "bounds": [lo, hi], "unit": unit}
                for n, (key, unit, lo, hi) in BASE_PARAMS.items()}

    # -- simulate, fit, score ----------------------------------------------------------
    def predict(self, ph: Physics, train_only: bool = False) -> dict[str, dict[str, np.ndarray]]:
        """Channels of the analysis-rate runs predicted by `ph`."""
        model = ReducedModel(ph, self.vt)
        out = {}
        for r in self.runs:
            if self._stop.is_set():
                raise _StopRequestedError
            n = segments(r)[0].stop if train_only else len(r.time)
            out[r.name] = model.simulate(r.time[:n], r.channel("h_span")[:n])
        return out

    def _residuals(self, ph: Physics) -> np.ndarray:
        if self._stop.is_set():
            raise _StopRequestedError
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
        nb = len(BASE_PARAMS)
        if multistart:
            # trial starts for the new effect's parameters, with the current base loop and
            # with the nominal one (the current base may have compensated for the effect)
            idx = [i for i, (o, *_rest) in enumerate(lay) if o == multistart]
            nominal = self._pack(dataclasses.replace(ph, open_loop=self.start.open_loop), lay)
            best, best_x = np.inf, x0
            for base in (x0[:nb], nominal[:nb]):
                for frac in (0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95, None):
                    x = x0.copy()
                    x[:nb] = base
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
        """Run the loop (in a worker thread; this thread reports progress). Ctrl-C (or a
        progress callback raising KeyboardInterrupt) stops the fits promptly and raises
        `DiagnosisInterrupted` with the rounds finished."""
        self._stop.clear()
        events: queue.SimpleQueue = queue.SimpleQueue()
        st = _State()
        worker = threading.Thread(target=self._loop, args=(st, events.put), daemon=True,
                                  name="vtable-diagnose")
        worker.start()
        try:
            while worker.is_alive() or not events.empty():
                try:
                    item = events.get(timeout=0.1)
                except queue.Empty:
                    continue
                self.progress(*item)
        except KeyboardInterrupt:
            self._stop.set()
            worker.join()
            self._stop.clear()
            raise DiagnosisInterrupted(self._partial(st)) from None
        except BaseException:  # a failing progress callback: stop the fits, then report it
            self._stop.set()
            worker.join()
            self._stop.clear()
            raise
        worker.join()
        if st.error is not None:
            raise st.error
        assert st.result is not None
        return st.result

    def _loop(self, st: _State, post: Callable[[tuple[int, int, str]], None]) -> None:
        try:
            st.result = self._run(st, lambda i, n, s: post((i, n, s)))
        except _StopRequestedError:
            pass
        except BaseException as e:  # handed to the caller's thread
            st.error = e

    def _detail(self, st: _State) -> Comparison:
        if st.cmp is None:
            st.cmp = self.score(st.current, detail=True)
        return st.cmp

    def _run(self, st: _State, progress: Callable[[int, int, str], None]) -> Diagnosis:
        steps = 1 + self.max_rounds * len(self.catalog)
        done = 0
        progress(done, steps, "fitting the starting model")
        current, _ = self.fit(self.start)
        self.start_fitted = current
        st.current = current
        done += 1
        st.cmp0 = self._detail(st)
        st.err = st.start_err = err = st.cmp0.error
        reason = ""
        for k in range(1, self.max_rounds + 1):
            todo = [e for e in self.catalog if not current.has(e)]
            if not todo:
                reason = "every catalog effect is in the model"
                break
            cmp_cur = self._detail(st)
            ranking: list[Candidate] = []

            def trial(name: str, base: Physics = current) -> Candidate:
                cand, train = self.fit(base.with_effect(name), multistart=name)
                return Candidate(name, dict(cand.effects[name]), self.score(cand).error, train,
                                 "", len(effect(name).params), cand, self.at_bounds(cand))

            # candidates are independent: fit them on both cores (the kernel releases the
            # GIL); on a stop, pending fits are cancelled and running ones end at their next
            # simulation
            pool = ThreadPoolExecutor(max_workers=WORKERS)
            try:
                futures = {pool.submit(trial, name): name for name in todo}
                for fut in as_completed(futures):
                    ranking.append(fut.result())
                    done += 1
                    progress(done, steps, f"round {k}: tried {futures[fut]}")
            finally:
                pool.shutdown(wait=True, cancel_futures=True)
            ranking.sort(key=lambda c: c.score)
            for c in ranking:
                c.evidence = _evidence(c, err, self.floor, cmp_cur)
            best = ranking[0]
            gain = err - best.error_after
            needed = max(MIN_GAIN * (err - self.floor), FLOOR_GAIN * self.floor,
                         PENALTY * best.n_params)
            if gain > needed:
                st.rounds.append(Round(ranking, best.effect, best.error_after, err))
                current, err = best.physics, best.error_after
                st.current, st.err, st.cmp = current, err, None
                progress(done, steps, f"round {k} done: added {best.effect}")
            else:
                st.rounds.append(Round(ranking, None, err, err))
                reason = (f"the best candidate ({best.effect}) would lower the held-out error "
                          f"by {gain:.2%}, less than the {needed:.2%} the noise floor "
                          f"({self.floor:.1%}) and the parsimony penalty require")
                progress(done, steps, f"round {k} done: nothing added")
                break
        if not reason:
            reason = f"stopped after {self.max_rounds} rounds"
        final_cmp = self._detail(st)
        progress(steps, steps, "done")
        return self._diagnosis(st, final_cmp, reason)

    def _diagnosis(self, st: _State, final_cmp: Comparison | None, reason: str,
                   interrupted: bool = False) -> Diagnosis:
        current = st.current or self.start
        err = st.err
        added = [r.added for r in st.rounds if r.added]
        floor = self.floor
        unexp = None
        if final_cmp is not None:
            unexp = unexplained(final_cmp)
        elif err is not None and not (floor > 0 and err <= NOISE_FACTOR * floor):
            unexp = {"ratio_to_floor": err / floor if floor > 0 else float("inf"),
                     "where": "not localised (the diagnosis was interrupted)"}
        parts = []
        if interrupted:
            parts.append(f"interrupted after round {len(st.rounds)}"
                         + ("" if err is not None else ", before the starting model was fitted")
                         + "; the diagnosis is incomplete")
        if added:
            parts.append(f"added {', '.join(added)}: held-out error {st.start_err:.2%} -> "
                         f"{err:.2%} (noise floor {floor:.2%})")
        if err is not None:
            if unexp is None:
                lead = "no missing effect" if not added else "no further missing effect"
                if interrupted:
                    lead = "so far within the noise"
                parts.append(f"{lead}: the final held-out error {err:.2%} is within "
                             f"{NOISE_FACTOR:g} x the noise floor ({floor:.2%})")
            else:
                parts.append(f"a residual remains unexplained: the final held-out error "
                             f"{err:.2%} is {unexp['ratio_to_floor']:.1f} x the noise floor "
                             f"({floor:.2%}), above the {NOISE_FACTOR:g} x noise alone explains;"
                             f" it lives in {unexp['where']}")
        if reason:
            parts.append(reason)
        return Diagnosis(list(self.start.effects), st.start_err, floor, list(st.rounds),
                         current, err, "; ".join(parts), st.cmp0, final_cmp,
                         self.base_table(current), unexp, list(self.notes), interrupted)

    def _partial(self, st: _State) -> Diagnosis:
        """The diagnosis of the rounds that finished, without another simulation."""
        return self._diagnosis(st, st.cmp if st.current is not None else None, "",
                               interrupted=True)


def _evidence(c: Candidate, err: float, floor: float, cmp: Comparison) -> str:
    worst = cmp.worst_groups(2)
    where = ", ".join(g for g, _ in worst)
    band = cmp.worst_band(worst[0][0]) if worst else None
    removed = (err - c.error_after) / max(err - floor, 1e-12)
    params = ", ".join(f"{k} = {v:.3g} {p.unit}" for (k, v), p in
                       zip(c.params.items(), effect(c.effect).params, strict=True))
    return (f"residual concentrated in {where}" + (f" at {band[0]}" if band else "")
            + f"; adding {c.effect} removes {removed:.0%} of it (held-out error {err:.2%} -> "
              f"{c.error_after:.2%}); fitted {params}")


def diagnose(runs: Sequence[Run], start_effects: Sequence[str] = (), **kw) -> Diagnosis:
    return Diagnoser(runs, start_effects, **kw).diagnose()


def localise(d: Diagnosis) -> str:
    return localisation_text(d.comparison_start) if d.comparison_start else ""
