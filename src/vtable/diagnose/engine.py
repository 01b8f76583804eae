"""The diagnosis loop: calibrate the base, then for every catalog effect the model lacks,
add it, fit its parameters together with the whole calibrated base (the servo loop, the
specimen's modes, damping and mass, the platen's mass, and its centre-of-mass height and
pitch inertia when the effect lets it pitch: `vtable.diagnose.calibration`) and the effects
already in the model on the training segments of the campaign, score on the held-out
segments, rank by held-out gain, add the best that passes the selection rule, repeat.
Nonlinear candidates (an order of magnitude costlier to simulate) are screened: if a few
least-squares steps from their best start do not lower the training cost by 1 %, their fit
stops there (`TableModel`'s `baseline`).

Selection rule (`SELECTION`), on the held-out segments and on the squared scale where
sensor noise and a systematic error add (e² = mean over runs and channel groups of the
squared NRMS error; the noise alone costs f², the current model's systematic residual is
e² - f²; `compare.held_out_gain`). A candidate is added only if its gain e²_current -
e²_candidate

1. exceeds `Z_NOISE` (5) standard errors of what the held-out noise produces between the two
   predictions: both were fitted on the training segments, so the held-out noise enters the
   gain only as 2 n·(ŷ_c - ŷ)/||y||², Gaussian with a variance the noise σ of every group
   gives (a likelihood-ratio test against the noise floor; white noise at the analysis rate);
2. removes at least `MIN_SHARE` (20 %) of the current model's systematic residual: the
   current model is itself calibrated, so this is what the effect explains that recalibrating
   the base cannot, and a small patch of a model-form difference is not a missing effect;
3. is at least 5 % of what the noise alone costs (f²; the reduced model's resolution,
   (0.5 %)², counts as noise where the sensors are quieter: `MODEL_RESOLUTION`): refitting
   the base and an effect to other noise moves a held-out error by less;

and (4) its fit is sound: no fitted effect parameter within 1 % of a bound (fitted scale),
correlated beyond 0.95 with a base parameter, or without influence on the data
(Gauss-Newton covariance at the solution). A candidate failing (4) is flagged in the
ranking and not added on that evidence; the next sound one may be. Base parameters at a
bound are flagged too but do not block: they say the model still lacks something.

Training = the first 60 % of every run (at most its first 30 s: a few parameters need no more,
and every simulated second costs each fit), held out = the last 40 % (`compare.segments`),
both at the analysis rate (`compare.analysis_run`: runs faster than 200 Hz are anti-alias
filtered and resampled to 200 Hz; slower ones keep their rate).

The verdict is honest about what is left: the final model's held-out error is compared
with the noise floor by `compare.UNEXPLAINED_RULE` (consistent when err ≤ 2 × floor: noise and
a systematic error add in quadrature, err² ≈ floor² + sys²). Above that, `unexplained`
gives the ratio and where the residual lives, and the verdict says a residual remains
unexplained; "no missing effect" is said only when the final error is consistent with the
noise. A candidate whose fitted parameters sit within 1 % of a bound (on the fitted scale:
logarithmic for log parameters) is flagged: the fit may have pushed the effect where it is
not physics but a patch.

The candidates of a round (and the backward step's refits) are fitted in `workers`
processes (`vtable.diagnose.workers`; threads when a user's effect was registered from code
rather than a file, and in the loop's own thread with `workers=1`).

Ctrl-C: the loop runs in a thread of its own; the caller's thread only waits and reports
progress. An interrupt sets the stop flags (this process's and the workers' shared one)
that the residual function checks between simulations, pending candidate fits are
cancelled, and `DiagnosisInterrupted` (a KeyboardInterrupt) carries the rounds finished.
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from vtable.diagnose.calibration import Calibration
from vtable.diagnose.campaign import MODEL_RESOLUTION, Campaign, check_campaign
from vtable.diagnose.compare import (
    NOISE_FACTOR,
    UNEXPLAINED_RULE,
    Comparison,
    Gain,
    compare,
    held_out_gain,
    localisation_text,
    unexplained,
)
from vtable.diagnose.model import BASE_PARAMS, SCREEN, StopRequestedError, TableModel
from vtable.effects.physics import Physics, nominal_open_loop
from vtable.effects.registry import get as effect
from vtable.effects.registry import names as registered
from vtable.errors import VtableError
from vtable.runs.model import Run

__all__ = ["BASE_PARAMS", "Candidate", "Diagnoser", "Diagnosis", "DiagnosisInterrupted",
           "Round", "Stage", "check_campaign", "diagnose", "localise"]

Z_NOISE = 5.0  # the held-out gain must stand 5 standard errors above what noise produces ...
MIN_SHARE = 0.2  # ... remove 20 % of the current model's systematic residual (squared) ...
#: ... and be 5 % of what the noise alone costs (f²), the reduced model's own resolution
#: (`MODEL_RESOLUTION`, a floor below which it cannot tell physics from its approximations)
#: counting as noise when the sensors are quieter
NOISE_SHARE = 0.05
SELECTION = (f"an effect is added when, on the held-out last 40 % of every run and on the "
             f"scale where sensor noise and a systematic error add (the mean over runs and "
             f"channel groups of the squared NRMS error), its gain over the calibrated "
             f"current model (1) exceeds {Z_NOISE:g} standard errors of what the held-out "
             f"noise alone produces between the two predictions (a likelihood-ratio test "
             f"against the noise floor), (2) removes at least {MIN_SHARE:.0%} of the current "
             f"model's systematic residual (error^2 - floor^2) and (3) is at least "
             f"{NOISE_SHARE:.0%} of what the noise alone costs (floor^2; at least "
             f"({MODEL_RESOLUTION:.1%})^2, what the reduced model cannot resolve): refitting "
             "the base and an effect to other noise moves a held-out error by less; and "
             "its fit is sound: none of its own parameters within 1 % of a bound, correlated "
             "beyond 0.95 with a base parameter, or without influence on the data. The best "
             "such candidate (largest gain) is added. After each addition every effect added "
             "earlier is tested the same way against the model without it (refitted) and "
             "removed when it no longer passes")
WORKERS = min(2, os.cpu_count() or 1)
ERROR_DEFINITION = ("mean over runs and channel groups of the normalised RMS error "
                    "||model - measured|| / ||measured|| on the held-out last 40 % of every "
                    "run, at the analysis rate (runs faster than 200 Hz anti-alias filtered and "
                    "resampled to 200 Hz); the noise floor is the same measure for the sensor "
                    "noise alone")


@dataclass
class Stage:
    """A model the diagnosis went through, with what it predicts for every run (analysis
    rate) and how that compares with the measurements: the report and the recording render
    these without simulating again."""

    label: str
    physics: Physics = field(repr=False)
    predictions: dict[str, dict[str, np.ndarray]] = field(repr=False)
    comparison: Comparison | None = None


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
    predictions: dict | None = field(default=None, repr=False)
    screened: bool = False  # its first fit steps lowered the training cost < 1 %: stopped
    cost: float = float("nan")  # the fit's training cost (residuals and priors)
    gain: Gain | None = None  # its held-out gain over the current model (`SELECTION`)

    @property
    def blocking(self) -> list[str]:
        """The flags on the candidate's own parameters (at a bound, not identifiable, no
        valid model): it is not added on that evidence. Flags on base parameters (a
        calibrated value at its bound) are reported but do not block: they say the model
        still lacks something, not that this effect is wrong."""
        return [f for f in self.flags if f.startswith((f"{self.effect}.", "no valid model"))]

    @property
    def score(self) -> float:
        """The ranking's key: the held-out mean squared NRMS error (`Gain.e2_candidate`)."""
        return self.gain.e2_candidate if self.gain is not None else float("inf")

    def failing(self) -> list[str]:
        """The statistical criteria of `SELECTION` this candidate's gain does not meet."""
        return failing(self.gain)


def failing(g: Gain | None) -> list[str]:
    """The statistical criteria of `SELECTION` a held-out gain does not meet (empty: it
    passes)."""
    if g is None:
        return ["no valid model"]
    out = []
    if not g.z > Z_NOISE:
        out.append(f"its gain is {g.z:.1f} standard errors of the noise (needs {Z_NOISE:g})")
    if not g.gain >= MIN_SHARE * g.systematic:
        out.append(f"it removes {max(g.share, 0):.0%} of the systematic residual (needs "
                   f"{MIN_SHARE:.0%})")
    f2 = max(g.f2, MODEL_RESOLUTION**2)
    if not g.gain >= NOISE_SHARE * f2:
        out.append(f"its gain is {max(g.gain, 0) / f2:.0%} of what the noise alone costs "
                   f"(needs {NOISE_SHARE:.0%})" + ("" if g.f2 >= f2 else
                                                   f"; the noise taken at the reduced model's "
                                                   f"resolution, {MODEL_RESOLUTION:.1%}"))
    return out


@dataclass
class Round:
    ranking: list[Candidate]
    added: str | None
    error: float
    before: float
    skipped: dict[str, str] = field(default_factory=dict)  # effect -> why it cannot apply
    #: effects added earlier and removed after this round's addition: effect -> why
    removed: dict[str, str] = field(default_factory=dict)


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
    stages: list[Stage] = field(default_factory=list, repr=False)
    runs: list[Run] = field(default_factory=list, repr=False)

    @property
    def final_effects(self) -> list[str]:
        return list(self.final.effects)

    def history(self) -> list[tuple[str, float]]:
        if self.start_error is None:
            return []
        h = [("start", self.start_error)]
        for r in self.rounds:
            if r.added:
                h.append((r.added + "".join(f" - {e}" for e in r.removed), r.error))
        return h

    def to_json(self) -> dict[str, Any]:
        """The keys of docs/diagnosis-json.md (and more)."""
        return {
            "format": "vtable-diagnosis/1",
            "start_effects": self.start_effects,
            "start_error": self.start_error,
            "noise_floor": self.noise_floor,
            "base": self.base,
            "rounds": [{"ranking": [{"effect": c.effect, "error_after": c.error_after,
                                     "train_error": c.train_error, "params": c.params,
                                     "n_params": c.n_params, "evidence": c.evidence,
                                     "flags": c.flags, "screened": c.screened,
                                     "gain": _gain_json(c)}
                                    for c in r.ranking],
                        "added": r.added, "removed": r.removed, "error": r.error,
                        "error_before": r.before, "skipped": r.skipped}
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
            "selection_rule": SELECTION,
        }


class DiagnosisInterrupted(KeyboardInterrupt):
    """Ctrl-C during `Diagnoser.diagnose`: `partial` is the diagnosis of the rounds that
    finished (`interrupted` True)."""

    def __init__(self, partial: Diagnosis) -> None:
        super().__init__(partial.verdict)
        self.partial = partial


@dataclass
class _State:
    """What the loop has established so far (read by the caller on an interrupt)."""

    current: Physics | None = None
    err: float | None = None
    start_err: float | None = None
    cmp0: Comparison | None = None
    cmp: Comparison | None = None  # detailed comparison of `current`, when made
    rounds: list[Round] = field(default_factory=list)
    stages: list[Stage] = field(default_factory=list)
    result: Diagnosis | None = None
    error: BaseException | None = None


class Diagnoser:
    """fit/score on a campaign; `diagnose()` runs the loop. `workers`: the processes the
    candidates are fitted in (default `WORKERS`, two on this project's machines; 1 fits
    them one after the other in the loop's thread).

    `runs` are the campaign as read; `self.runs` the same at the analysis rate, and
    `self.notes` what the readers reported, the resampling done and the channels left out.
    """

    def __init__(self, runs: Sequence[Run], start_effects: Sequence[str] = (),
                 catalog: Sequence[str] | None = None,
                 progress: Callable[[int, int, str], None] | None = None,
                 max_rounds: int = 4, calibration: Calibration | None = None,
                 workers: int | None = None) -> None:
        self.campaign = Campaign.of(runs)
        self.workers = WORKERS if workers is None else max(1, int(workers))
        self._procs = None
        self._file = None  # the campaign pickled for the worker processes
        self.source_runs, self.runs = self.campaign.source_runs, self.campaign.runs
        for e in start_effects:
            effect(e)
        self.notes = self.campaign.notes
        self.vt = self.campaign.table
        self.specimen = self.runs[0].specimen()
        self.start = Physics(nominal_open_loop(self.vt), self.specimen,
                             {e: {} for e in start_effects})
        self.catalog = list(catalog or registered())
        for e in self.catalog:
            effect(e)
        self.progress = progress or (lambda i, n, s: None)
        self.max_rounds = max_rounds
        self.floor = self.campaign.floor
        self.calibration = calibration or Calibration()
        self._stop = threading.Event()

    def model(self, start: Physics, multistart: str | None = None,
              baseline: float | None = None, seed: dict[str, float] | None = None
              ) -> TableModel:
        """The estimator the loop fits (sharing this diagnosis's stop flag)."""
        return TableModel(start=start, multistart=multistart, stop=self._stop,
                          calibration=self.calibration, baseline=baseline, seed=seed)

    def fit(self, ph: Physics, multistart: str | None = None,
            baseline: float | None = None, seed: dict[str, float] | None = None
            ) -> TableModel:
        """Fit `ph` (see `TableModel`): the fitted estimator (`physics_`, `train_error_`,
        `flags_`, `cost_`, `screened_`)."""
        return self.model(ph, multistart, baseline, seed).fit(self.campaign)

    def _fit_here(self, start: Physics, name: str, baseline: float | None,
                  seed: dict[str, float] | None) -> tuple:
        """`workers._fit` in this process."""
        from vtable.diagnose.workers import fitted

        return fitted(self.model(start, name, baseline, seed), self.campaign)

    def _campaign_file(self):
        if self._file is None:
            from vtable.diagnose.workers import CampaignFile

            self.campaign.noise  # noqa: B018 (computed before pickling, with the table)
            self._file = CampaignFile(self.campaign)
        return self._file

    def _pool(self):
        """The worker processes for this diagnosis's candidates (`workers.CandidatePool`),
        or None: one worker, or an effect registered from code (not from a file another
        process can load)."""
        from vtable.effects.registry import is_user, source_file

        if self.workers < 2:
            return None
        files = []
        for e in self.catalog:
            if is_user(e):
                f = source_file(e)
                if f is None:
                    return None
                files.append(f)
        from vtable.diagnose.workers import CandidatePool

        pool = CandidatePool.get(self.workers, tuple(sorted(set(files))))
        if self._procs is None:  # this diagnosis's first round: a stop left from before goes
            pool.stop.clear()
        self._procs = pool
        return pool

    def _inapplicable(self, ph: Physics) -> str:
        """Why a model cannot be built for this campaign's table (an effect needing a
        motion the platen has not, say), or ''."""
        from vtable.effects.reduced import ReducedModel

        try:
            ReducedModel(ph, self.vt)
        except VtableError as e:
            return str(e)
        return ""

    def _linear(self, ph: Physics) -> bool:
        from vtable.effects.reduced import ReducedModel

        try:
            return ReducedModel(ph, self.vt).linear
        except VtableError:
            return False

    def _model(self) -> TableModel:
        m = TableModel(stop=self._stop, calibration=self.calibration)
        m.vt, m.declared = self.vt, self.campaign.specimen
        return m

    def at_bounds(self, ph: Physics) -> list[str]:
        return self._model().at_bounds(ph)

    def base_table(self, ph: Physics) -> dict[str, dict[str, Any]]:
        return self._model().base_table(ph)

    def predict(self, ph: Physics) -> dict[str, dict[str, np.ndarray]]:
        """Channels of the analysis-rate runs predicted by `ph`."""
        return self._model()._predict(ph, self.campaign)

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
            self._halt()
            worker.join()
            self._stop.clear()
            self._close_file()
            raise DiagnosisInterrupted(self._partial(st)) from None
        except BaseException:  # a failing progress callback: stop the fits, then report it
            self._halt()
            worker.join()
            self._stop.clear()
            self._close_file()
            raise
        worker.join()
        self._close_file()
        if st.error is not None:
            raise st.error
        assert st.result is not None
        return st.result

    def _close_file(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None

    def _halt(self) -> None:
        """Stop the fits: this process's and the worker processes' (at their next
        simulation)."""
        self._stop.set()
        if self._procs is not None:
            self._procs.stop.set()

    def _loop(self, st: _State, post: Callable[[tuple[int, int, str]], None]) -> None:
        try:
            with threadpool_limits(limits=1, user_api="blas"):  # small matrices: see model
                st.result = self._run(st, lambda i, n, s: post((i, n, s)))
        except StopRequestedError:
            pass
        except BaseException as e:  # handed to the caller's thread
            st.error = e

    def _detail(self, st: _State) -> Comparison:
        """The detailed comparison of the current model (from its stage's predictions)."""
        if st.cmp is None:
            stage = st.stages[-1]
            st.cmp = compare(stage.predictions, self.runs, scored="held", floor=self.floor,
                             detail=True)
            stage.comparison = st.cmp
        return st.cmp

    def _run(self, st: _State, progress: Callable[[int, int, str], None]) -> Diagnosis:
        steps = 1 + self.max_rounds * len(self.catalog)
        done = 0
        progress(done, steps, "fitting the starting model")
        self._pool()  # the workers start while this process fits the starting model
        fitted = self.fit(self.start)
        current, cost = fitted.physics_, fitted.cost_
        self.notes += [f"starting model: {f}" for f in fitted.flags_]
        self.start_fitted = current
        st.current = current
        st.stages.append(Stage("start", current, self.predict(current)))
        done += 1
        st.cmp0 = self._detail(st)
        st.err = st.start_err = err = st.cmp0.error
        reason = ""
        seeds: dict[str, dict[str, float]] = {}  # each candidate's last fitted parameters
        spent: dict[str, float] = {}  # each candidate's last fit's CPU seconds
        backward: list[str] = []  # effects added before the last one: tested without each
        k = 0
        while k < self.max_rounds:
            k += 1
            todo, skipped = [], {}
            for e in self.catalog:
                if current.has(e):
                    continue
                why = self._inapplicable(current.with_effect(e))
                if why:
                    skipped[e] = why
                else:
                    todo.append(e)
            if not todo and not backward:
                reason = "every catalog effect is in the model"
                break
            cmp_cur = self._detail(st)

            def judged(name: str, fitted: tuple) -> Candidate:
                """The candidate a fit (`workers._fit`'s tuple) makes, scored held out."""
                cand, train, flags, cost_, screened, pred, secs = fitted
                spent[name] = secs
                if isinstance(pred, Exception):  # the fit found no model it could build
                    return Candidate(name, dict(cand.effects[name]), float("inf"), train, "",
                                     len(effect(name).params), cand,
                                     [f"no valid model found: {pred}"], None)
                err = compare(pred, self.runs, scored="held", floor=self.floor).error
                gain = held_out_gain(st.stages[-1].predictions, pred, self.runs,
                                     self.campaign.noise)
                return Candidate(name, dict(cand.effects[name]), err, train, "",
                                 len(effect(name).params), cand, flags, pred, screened,
                                 cost_, gain)

            def task(name: str, base: Physics = current, baseline: float = cost) -> tuple:
                start = base.with_effect(name)
                # linear models fit in a second: only the costly nonlinear ones are screened
                return (start, name, None if self._linear(start) else baseline,
                        seeds.get(name))

            # the backward step for the last addition (each earlier effect left out, the
            # model refitted) runs beside this round's candidates: a removal, rare, makes
            # the round start again from the smaller model. The costliest fits go first
            # (what each took last round; nonlinear ones before linear ones in the first),
            # so that no long fit starts last on an idle core.
            todo.sort(key=lambda e: -spent.get(e, 0.0 if self._linear(current.with_effect(e))
                                               else 1.0))
            jobs = [(("without", e), (current.without(e), None, None, None)) for e in backward]
            jobs += [(("add", e), task(e)) for e in todo]
            ranking: list[Candidate] = []
            left: dict[str, tuple] = {}
            for (kind, name), fitted in self._dispatch(jobs):
                if kind == "without":
                    left[name] = fitted
                    continue
                ranking.append(judged(name, fitted))
                done += 1
                progress(done, steps, f"round {k}: tried {name}")
            dropped = self._backward(st, backward, left, progress, done, steps, k)
            backward = []
            if dropped is not None:
                current, err, cost = dropped
                k -= 1  # this round's candidates were fitted to the larger model: again
                continue
            if not ranking:
                reason = "every catalog effect is in the model"
                break
            ranking.sort(key=lambda c: c.score)
            seeds.update({c.effect: c.params for c in ranking if not c.screened})
            # SELECTION: the candidate with the largest held-out gain that passes the
            # statistical criteria and whose fit is sound (no parameter at a bound, none
            # entangled with the base) is added
            best = next((c for c in ranking if not c.failing() and not c.blocking), None)
            for c in ranking:
                c.evidence = _evidence(c, err, self.floor, cmp_cur)
                if c is not best:
                    c.predictions = None  # only the added model's predictions are kept
            if best is not None:
                st.rounds.append(Round(ranking, best.effect, best.error_after, err, skipped))
                current, err, cost = best.physics, best.error_after, best.cost
                st.current, st.err, st.cmp = current, err, None
                st.stages.append(Stage(f"{len(st.stages)}_{best.effect}", current,
                                       best.predictions))
                progress(done, steps, f"round {k} done: added {best.effect}")
                backward = [e for e in current.effects
                            if e != best.effect and e not in self.start.effects]
            else:
                st.rounds.append(Round(ranking, None, err, err, skipped))
                top = ranking[0]
                what = (f"the best candidate ({top.effect}) would change the held-out error "
                        f"{err:.2%} -> {top.error_after:.2%}")
                if top.failing():
                    reason = f"{what}, not a gain the noise cannot produce: " + \
                        "; ".join(top.failing())
                else:
                    reason = (f"{what}, but it is not added on that evidence: "
                              + "; ".join(top.blocking))
                passing = [c for c in ranking if not c.failing()]
                if passing and top.failing():
                    reason += ("; the candidates whose gain would count are not sound fits: "
                               + "; ".join(f"{c.effect}: {'; '.join(c.blocking)}"
                                           for c in passing))
                reason += " (the base recalibrated with every candidate)"
                progress(done, steps, f"round {k} done: nothing added")
                break
        if backward:  # the rounds ran out right after an addition
            left = dict((name, fitted) for (_, name), fitted in self._dispatch(
                [(("without", e), (current.without(e), None, None, None)) for e in backward]))
            self._backward(st, backward, left, progress, done, steps, k)
        if not reason:
            reason = f"stopped after {self.max_rounds} rounds"
        final_cmp = self._detail(st)
        progress(steps, steps, "done")
        return self._diagnosis(st, final_cmp, reason)

    def _dispatch(self, jobs: list[tuple[Any, tuple]]):
        """Run fits (key, (start, multistart effect, baseline, seed)) on every core and
        yield (key, `workers._fit`'s tuple) as each finishes: in the worker processes, or
        in threads when a user's effect cannot be loaded in another process. On a stop,
        pending fits are cancelled and running ones end at their next simulation."""
        if not jobs:
            return
        if self.workers == 1:  # one after the other, here
            for key, args in jobs:
                yield key, self._fit_here(*args)
            return
        pool = self._pool()
        threads = None if pool is not None else ThreadPoolExecutor(max_workers=self.workers)
        futures: dict = {}
        try:
            for key, args in jobs:
                fut = (pool.fit(self._campaign_file().path, *args, self.calibration)
                       if pool is not None else threads.submit(self._fit_here, *args))
                futures[fut] = key
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
        finally:
            if threads is not None:
                threads.shutdown(wait=True, cancel_futures=True)
            for fut in futures:
                fut.cancel()

    def _backward(self, st: _State, names: list[str], fitted: dict[str, tuple],
                  progress, done: int, steps: int, k: int):
        """The backward step: the current model against each fit without one of `names`;
        the first effect whose keeping is not a gain `SELECTION` would count is removed
        (recorded in the last round). Returns (model, error, cost) after a removal, else
        None."""
        pred_cur = st.stages[-1].predictions
        for name in names:
            physics, _, _, cost, _, pred, _ = fitted[name]
            if isinstance(pred, Exception):
                continue
            fails = failing(held_out_gain(pred, pred_cur, self.runs, self.campaign.noise))
            if not fails:
                continue
            err = compare(pred, self.runs, scored="held", floor=self.floor).error
            rnd = st.rounds[-1]
            rnd.removed[name] = (
                f"no longer needed once the later effects are in: without it (base "
                f"recalibrated) the held-out error is {err:.2%}; keeping it is not a gain "
                "the noise cannot produce: " + "; ".join(fails))
            rnd.error = err
            st.current, st.err, st.cmp = physics, err, None
            st.stages.append(Stage(f"{len(st.stages)}_without_{name}", physics, pred))
            progress(done, steps, f"round {k}: removed {name}")
            return physics, err, cost
        return None

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
        removed = [e for r in st.rounds for e in r.removed]
        if added:
            parts.append(f"added {', '.join(added)}"
                         + (f" (later removed: {', '.join(removed)})" if removed else "")
                         + f": held-out error {st.start_err:.2%} -> {err:.2%} (noise floor "
                           f"{floor:.2%})")
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
                         self.base_table(current), unexp, list(self.notes), interrupted,
                         list(st.stages), list(self.runs))

    def _partial(self, st: _State) -> Diagnosis:
        """The diagnosis of the rounds that finished, without another simulation."""
        return self._diagnosis(st, st.cmp if st.current is not None else None, "",
                               interrupted=True)


def _gain_json(c: Candidate) -> dict[str, float] | None:
    g = c.gain
    if g is None:
        return None
    return {"mean_sq_error_before": g.e2_current, "mean_sq_error_after": g.e2_candidate,
            "mean_sq_noise": g.f2, "gain": g.gain, "noise_se": g.se, "z": g.z,
            "share_of_systematic": g.share, "passes": not c.failing()}


def _evidence(c: Candidate, err: float, floor: float, cmp: Comparison) -> str:
    if not np.isfinite(c.error_after):
        return "; ".join(c.flags)
    if c.screened:
        return (f"screened out: its first least-squares steps from the best start on its "
                f"grid lowered the training cost by less than {SCREEN:.0%} (held-out error "
                f"{err:.2%} -> {c.error_after:.2%}, not refined further)")
    worst = cmp.worst_groups(2)
    where = ", ".join(g for g, _ in worst)
    band = cmp.worst_band(worst[0][0]) if worst else None
    g = c.gain
    removed = f"{max(g.share, 0.0):.0%}" if g is not None and np.isfinite(g.share) else "all"
    z = f", {g.z:.1f} standard errors of the noise" if g is not None else ""
    params = ", ".join(f"{k} = {v:.3g} {p.unit}" for (k, v), p in
                       zip(c.params.items(), effect(c.effect).params, strict=True))
    return (f"residual concentrated in {where}" + (f" at {band[0]}" if band else "")
            + f"; adding {c.effect} removes {removed} of its systematic part (held-out error "
              f"{err:.2%} -> {c.error_after:.2%}{z}); fitted {params}")


def diagnose(runs: Sequence[Run], start_effects: Sequence[str] = (), **kw) -> Diagnosis:
    return Diagnoser(runs, start_effects, **kw).diagnose()


def localise(d: Diagnosis) -> str:
    return localisation_text(d.comparison_start) if d.comparison_start else ""
