"""The diagnosis loop: calibrate the base, then for every catalog effect the model lacks,
add it, fit its parameters together with the whole calibrated base (`calibration`) and
the effects already in the model on the training segments, score on the held-out ones,
add the best that passes the selection rule (`selection.SELECTION`), repeat; after each
addition, test the earlier ones again without it (the backward step).

Each round's candidates are screened before they are fitted in full (`_candidates`): a
nonlinear one only where the runs show amplitude dependence (`screen`; on a model
nonlinear itself, only where the best linear candidate's fit still shows it), every one on
the current model linearised once for the round (`projected`); those that pass are refined
best first, and one that cannot win the round is kept where its screen left it. Training
is the first 60 % of every run (at most its first 30 s), held out the last 40 %, both at
the analysis rate (`sampling`). The verdict (`verdict`) is honest about what is left:
"no missing effect" only when the final error is within 2 x the noise floor
(`noise.UNEXPLAINED_RULE`); above that, where the residual lives.

The fits run as Dask tasks (`pool.Fits`, `workers`). Ctrl-C: the loop runs in a thread of
its own (`pool.in_thread`); an interrupt sets the stop flags every fit checks between
simulations, cancels what has not started, and `DiagnosisInterrupted` carries the rounds.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from vtable.diagnose.backward import backward_step
from vtable.diagnose.bounds import leaning_start, pushed_beyond, widened
from vtable.diagnose.calibration import Calibration
from vtable.diagnose.campaign import Campaign, check_campaign
from vtable.diagnose.compare import compare
from vtable.diagnose.evidence import evidence_view, started
from vtable.diagnose.judge import admissible, judged, not_fitted, select
from vtable.diagnose.model import BASE_PARAMS, TableModel, one_blas_thread, refit_without
from vtable.diagnose.pool import WORKERS, Fits, in_thread
from vtable.diagnose.projected import Frame
from vtable.diagnose.prose import nothing_added
from vtable.diagnose.reading import force_reading
from vtable.diagnose.residuals import StopRequestedError
from vtable.diagnose.result import (
    ERROR_DEFINITION,
    Candidate,
    Diagnosis,
    DiagnosisInterrupted,
    DiagnosisStage,
    Round,
    localise,
)
from vtable.diagnose.screen import linear_explains, nonlinearity_evidence
from vtable.diagnose.selection import LATE, failing
from vtable.diagnose.states import split, unexplained
from vtable.diagnose.statistics import Comparison
from vtable.diagnose.verdict import State, diagnosis_of
from vtable.diagnose.workers import CandidateFit
from vtable.effects.registry import default_candidates
from vtable.effects.registry import get as effect
from vtable.errors import VtableError
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.runs.model import Run

#: a candidate that passed the screen is refined (fitted in full) unless its screened
#: training cost is above this many times that of an admissible refined candidate: its
#: fit would have to fall by as much to win the round
REFINE_FACTOR = 3.0

__all__ = ["BASE_PARAMS", "ERROR_DEFINITION", "WORKERS", "Candidate", "Diagnoser", "Diagnosis",
           "DiagnosisInterrupted", "DiagnosisStage", "Round", "check_campaign", "diagnose",
           "failing", "localise"]


class Diagnoser:
    """fit/score on a campaign; `diagnose()` runs the loop. `workers`: the processes of the
    local Dask cluster the candidates are fitted in (default `WORKERS`, two on this
    project's machines; 1 fits them one after the other in the loop's thread);
    `scheduler`: a Dask scheduler's address (a lab's cluster) to fit them on instead.

    `runs` are the campaign as read; `self.runs` the same at the analysis rate, and
    `self.notes` what the readers reported, the resampling done and the channels left out.
    """

    def __init__(self, runs: Sequence[Run], start_effects: Sequence[str] = (),
                 catalog: Sequence[str] | None = None,
                 progress: Callable[[int, int, str], None] | None = None,
                 max_rounds: int = 4, calibration: Calibration | None = None,
                 workers: int | None = None, scheduler: str | None = None) -> None:
        self.campaign = Campaign.of(runs)
        self.workers = WORKERS if workers is None else max(1, int(workers))
        self.source_runs, self.runs = self.campaign.source_runs, self.campaign.runs
        self.notes, self.vt = self.campaign.notes, self.campaign.table
        self.campaign.residual_change = None  # asked by this diagnosis (`states.unexplained`)
        self.specimen = self.runs[0].specimen()
        self.catalog = list(catalog or default_candidates())
        for e in self.catalog:
            effect(e)
        # the starting model's effects where the runs show them (as `compare --with`), the
        # candidates' defaults and what the runs show of them (`SELECTION`'s prior)
        self.start = started(Physics(nominal_open_loop(self.vt), self.specimen, {}),
                             start_effects, self.campaign, self.notes)
        self.table_view = evidence_view(self.vt, [e for e in self.catalog
                                                  if e not in start_effects],
                                        self.campaign, self.notes)
        self.progress, self.max_rounds = progress or (lambda i, n, s: None), max_rounds
        self.floor, self._spectra = self.campaign.floor, {}  # `compare`'s memo of the runs
        self.calibration = calibration or Calibration()
        self.fits = Fits(self.campaign, self.catalog, self.workers, self.calibration,
                         self.model, scheduler)
        self._stop = self.fits.stop
        #: each round's nonlinearity screen (`vtable.diagnose.screen`)
        self.screens: list = []
        #: the candidates whose screen passed in the last round: their training cost as a
        #: share of the model's they were screened on (what orders the next round's fits)
        self.promise: dict[str, float] = {}
        self._frames: dict[int, tuple] = {}  # the last round's fits' frames (`_frame`)

    def model(self, start: Physics, **kw) -> TableModel:
        """The estimator the loop fits (sharing this diagnosis's stop flag; `kw`:
        `TableModel`'s multistart, baseline, seed, frame, screen_only, begin, choose, and a
        calibration other than this diagnosis's)."""
        kw.setdefault("calibration", self.calibration)
        return TableModel(start=start, stop=self._stop, **kw)

    def fit(self, ph: Physics, **kw) -> TableModel:
        """Fit `ph` (see `TableModel`): the fitted estimator (`physics_`, `train_error_`,
        `flags_`, `cost_`, `screened_`)."""
        return self.model(ph, **kw).fit(self.campaign)

    def _inapplicable(self, ph: Physics) -> str:
        """Why a model cannot be built for this campaign's table (an effect needing a
        motion the platen has not, say), or ''."""
        try:
            ReducedModel(ph, self.vt, kernels=False)
        except VtableError as e:
            return str(e)
        return ""

    def _linear(self, ph: Physics) -> bool:
        try:
            return ReducedModel(ph, self.vt, kernels=False).linear
        except VtableError:
            return False

    def _nonlinear(self, current: Physics, e: str) -> bool:
        """Whether `e` brings a nonlinear part of its own to `current`
        (`ReducedModel.nonlinear_parts`), whatever nonlinear parts `current` has."""
        try:
            return (ReducedModel(current.with_effect(e), self.vt, kernels=False).nonlinear_parts
                    > ReducedModel(current, self.vt, kernels=False).nonlinear_parts)
        except VtableError:
            return True

    def _model(self, calibration: Calibration | None = None) -> TableModel:
        """An unfitted estimator on this campaign's table and declaration (for its tables
        of the base: `calibration`'s bounds, default this diagnosis's)."""
        m = TableModel.unfitted(self.campaign, calibration or self.calibration, self._stop)
        m.vt = self.vt  # the table of the campaign as read (`states.split` may replace it)
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
        st = State()
        try:
            in_thread(lambda post: self._loop(st, post), self.progress, self.fits.halt)
        except KeyboardInterrupt:
            self._stop.clear()
            self.fits.close()
            raise DiagnosisInterrupted(self._partial(st)) from None
        except BaseException:  # a failing progress callback: the fits stopped, reported
            self._stop.clear()
            self.fits.close()
            raise
        self.fits.close()
        if st.error is not None:
            raise st.error
        assert st.result is not None
        return st.result

    def _loop(self, st: State, post: Callable[[tuple[int, int, str]], None]) -> None:
        try:
            with one_blas_thread():  # small matrices: see model
                st.result = self._run(st, lambda i, n, s: post((i, n, s)))
        except StopRequestedError:
            pass
        except BaseException as e:  # handed to the caller's thread
            st.error = e

    def _detail(self, st: State) -> Comparison:
        """The detailed comparison of the current model (from its stage's predictions)."""
        if st.cmp is None:
            stage = st.stages[-1]
            st.cmp = compare(stage.predictions, self.runs, scored="held", floor=self.floor,
                             detail=True, memo=self._spectra)
            stage.comparison = st.cmp
        return st.cmp

    def _run(self, st: State, progress: Callable[[int, int, str], None]) -> Diagnosis:
        steps = 2 + self.max_rounds * len(self.catalog)
        done = 0
        progress(done, steps, "fitting the starting model")
        late = {e for e in self.catalog if effect(e).accumulates}
        drift = not set(self.catalog) - late  # the round of what accumulates over a run
        # the first round's candidates compiled by the workers meanwhile, nonlinear first
        first = [self.start.with_effect(e) for e in self._todo(self.start, late, drift)[0]]
        self.fits.warm(sorted(first, key=self._linear))
        fitted = self.fit(self.start)
        current, cost = fitted.physics_, fitted.cost_
        self.notes += [f"starting model: {f}" for f in fitted.flags_]
        self.start_fitted = current
        st.current = current
        st.stages.append(DiagnosisStage("start", current, self.predict(current)))
        done += 1
        st.cmp0 = self._detail(st)
        st.err = st.start_err = err = st.cmp0.error
        if (read := force_reading(self, st)) is not None:  # started from a force stage
            current, err, cost = read
        self.widened = None  # the starting model refitted with its leaning bounds widened
        lean = leaning_start(self, current)
        reason = ""
        # each candidate's last fitted parameters (first: what the runs show of them)
        seeds = {e: dict(v) for e, (v, _) in self.table_view.evidence.items()}
        spent: dict[str, float] = {}  # each candidate's last fit's CPU seconds
        backward: list[str] = []  # effects added before the last one: tested without each
        k = 0
        while True:
            if k >= self.max_rounds + drift:  # the rounds ran out: then what accumulates
                if drift or not late - set(current.effects):
                    break
                drift = True
            k += 1
            if drift:  # what accumulates: also where the model leaves a change unexplained
                self.campaign.residual_change = unexplained(self, st)
            todo, skipped = self._todo(current, late, drift)
            if not todo and not backward:
                if not drift and late - set(current.effects):
                    drift = True
                    continue
                reason = reason or "every catalog effect is in the model"
                break
            ranking, left, done = self._candidates(st, current, cost, todo, backward, seeds,
                                                   spent, lean, progress, done, steps, k)
            lean = None  # refitted in the first round
            widened = self.widened
            dropped = backward_step(self, st, backward, left, progress, done, steps, k)
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
            best = select(self, ranking, widened, err, self._detail(st))
            if best is not None:
                st.rounds.append(Round(ranking, best.effect, best.error_after, err, skipped))
                current, err, cost = best.physics, best.error_after, best.cost
                st.adopt(best.effect, current, err, best.predictions)
                progress(done, steps, f"round {k} done: added {best.effect}")
                backward = [e for e in current.effects
                            if e != best.effect and e not in self.start.effects]
                if (read := force_reading(self, st)) is not None:  # what the forces read
                    current, err, cost = read
                if drift:  # what accumulates is tried once, last
                    break
            else:
                st.rounds.append(Round(ranking, None, err, err, skipped))
                why = nothing_added(ranking, err, widened)
                progress(done, steps, f"round {k} done: nothing added")
                if not late or drift:  # the search ends (its first reason kept)
                    reason = reason or why
                    break
                drift, reason = True, why  # now what accumulates over a run
        self._frames = {}  # the last round's, never asked for
        if backward:  # the rounds ran out right after an addition
            left = dict((name, fitted) for (_, name), fitted in self.fits.dispatch(
                [(("without", e), refit_without(current, e, cost, self.campaign))
                 for e in backward]))
            backward_step(self, st, backward, left, progress, done, steps, k)
        reason = reason or f"stopped after {self.max_rounds} rounds"
        progress(steps - 1, steps, "testing whether the runs hold one plant")
        st.plants = split(self, st)
        final_cmp = self._detail(st)
        said = lambda s: progress(steps - 1, steps, s)  # noqa: E731
        said("testing the declarations the final model leans on")
        st.pushed = pushed_beyond(self, st.current, st.err, st.stages[-1].predictions) \
            if st.current is not None and self.calibration.enabled else []
        out = diagnosis_of(self, st, final_cmp, reason, said=said)  # then its checks' lines
        progress(steps, steps, "done")
        return out

    def _todo(self, current: Physics, late: set[str], drift: bool
              ) -> tuple[list[str], dict[str, str]]:
        """This round's candidates, and why each other catalog effect not in `current` is
        not one: it cannot enter the model, the runs cannot show it, or it is not this
        round's kind (what accumulates over a run is tried after the rest: `drift`)."""
        todo, skipped = [], {}
        for e in self.catalog:
            if current.has(e):
                continue
            why = self._inapplicable(current.with_effect(e)) or \
                effect(e).unsupported(self.campaign) or \
                (LATE[drift] if (e in late) != drift else None)
            if why:
                skipped[e] = why
            else:
                todo.append(e)
        return todo, skipped

    def _judged(self, st: State, name: str, fitted: CandidateFit, spent: dict[str, float],
                unrefined: str = "") -> Candidate:
        """The candidate a fit makes (`judge.judged`); its CPU seconds counted in `spent`."""
        spent[name] = spent.get(name, 0.0) + fitted.cpu_s if unrefined else fitted.cpu_s
        if fitted.frame is not None:  # should it be added (`_frame`)
            self._frames[id(fitted.physics)] = (fitted.physics, fitted.frame)
        return judged(name, fitted, st.stages[-1].predictions, self.campaign, self.floor,
                      self.table_view, unrefined)

    def _frame(self, current: Physics) -> Frame:
        """The round's frame: the one the fit of `current` brought (`workers.fitted`'s
        `frame_after`, made beside the last round's fits), else made here."""
        # by id: each entry holds its model, so no other object can have that id
        made, self._frames = self._frames.get(id(current)), {}
        return made[1] if made is not None else self._model().frame_of(current, self.campaign)

    def _candidates(self, st: State, current: Physics, cost: float, todo: list[str],
                    backward: list[str], seeds: dict, spent: dict, lean: tuple | None,
                    progress, done: int, steps: int, k: int
                    ) -> tuple[list[Candidate], dict[str, CandidateFit], int]:
        """A round's candidates, and the backward step's refits beside them: (the ranking,
        unsorted; the refits without each effect of `backward`; the progress count).

        Every candidate is screened on the current model linearised once for all of them
        (`projected`): a fit that does not lower the training cost by `SCREEN` cannot
        gain the 5 % of the noise's cost SELECTION asks (criterion 3). A nonlinear one is
        not tried where the runs show no amplitude dependence (`screen`), nor, on a model
        nonlinear itself, where the best linear candidate's fit leaves none (held back
        till then: `screen.linear_explains`). Those that pass are refined best first, the
        costliest first on the cores (`Fits.dispatch`'s `ahead`); one whose screened
        training cost is above `REFINE_FACTOR` times that of an admissible refined
        candidate cannot win the round and is kept as screened."""
        # the refits that need no frame go to the cores first, while the frame is taken
        early = [(("without", e), refit_without(current, e, cost, self.campaign))
                 for e in backward]
        if lean is not None:  # the starting model refitted with its leaning bounds widened
            early.insert(0, (("widened", ""), {"start": self.start, "calibration": lean[0]}))
        self.fits.begin(early)
        frame = self._frame(current)
        ranking: list[Candidate] = []
        screen = nonlinearity_evidence(self.campaign, st.stages[-1].predictions)
        self.screens.append(screen)
        nonlinear = [e for e in todo if self._nonlinear(current, e)]
        # kept out where the runs show no amplitude dependence; held back (fitted after the
        # linear ones) where the current model, nonlinear itself, may be showing a linear
        # one's, unless the best screen of the last round was nonlinear (likely the winner)
        lead = min((e for e in todo if e in self.promise), key=self.promise.get, default=None)
        hold = screen.present and screen.read and lead not in nonlinear and \
            not self._linear(current)
        out = [] if screen.present else nonlinear
        held = [e for e in nonlinear if hold and
                not self.campaign.apart(current.with_effect(e), current)]
        todo = [e for e in todo if e not in out and e not in held]

        def costliest(e: str) -> tuple:
            return (0, self.promise[e]) if e in self.promise else \
                (1, -spent.get(e, 1.0 if e in nonlinear else 0.0))
        for names in (todo, held):  # the costliest fits first (no long fit starts last on an
            # idle core): those whose screen passed last round, best first (`promise`: likely
            # refined in their task now); then by what each took last round (nonlinear first)
            names.sort(key=costliest)
        self.promise = {}

        def job(e: str, **kw) -> dict:
            return {"start": current.with_effect(e), "multistart": e, "seed": seeds.get(e),
                    "frame": frame, "frame_after": True, **kw}

        def refit(e: str) -> tuple:  # a screen that passed, refined from where it stopped
            return ("add", e), job(e, begin=passed[e].passed)

        def screened(e: str) -> dict:  # trained on another window (what accumulates):
            # fitted in full, costs would not compare
            return job(e, frame=None, frame_after=False) if \
                self.campaign.apart(current.with_effect(e), current) \
                else job(e, baseline=cost, screen_only=True)

        left: dict[str, CandidateFit] = {}
        passed: dict[str, CandidateFit] = {}  # screens that passed: refined if they can win
        fitted_now: list[Candidate] = []

        def collect(jobs: list, meanwhile: Callable[[], Any] | None = None,
                    spare: list | None = None) -> None:
            # a core the last screens leave idle refines the best that passed so far (not
            # one a refined fit already beats: `hopeful`), then takes `spare` (held ones)
            nonlocal done
            for (kind, name), fitted in self.fits.dispatch(
                    jobs, meanwhile=meanwhile, ahead=lambda: hopeful() + (spare or [])):
                if kind == "without":
                    left[name] = fitted
                    continue
                if kind == "widened":
                    self.widened = widened(self, lean, fitted)
                    continue
                done += 1
                if fitted.passed is None:  # screened out, refined at once, or no valid model
                    c = self._judged(st, name, fitted, spent)
                    ranking.append(c)
                    fitted_now.append(c)
                    progress(done, steps, f"round {k}: tried {name}")
                    if not c.screened and np.isfinite(fitted.cost):  # refined in its task
                        self.promise[name] = fitted.cost / cost
                else:
                    passed[name] = fitted
                    spent[name] = fitted.cpu_s
                    self.promise[name] = fitted.cost / cost

        def refined() -> list[Candidate]:  # refined in their screen's task and sound
            return [c for c in fitted_now if not c.screened and admissible(self, c, self.widened)
                    and not self.campaign.apart(c.physics, current)]

        def can_win(e: str, best: Candidate | None) -> bool:  # a passed screen is refined
            # unless its cost is above REFINE_FACTOR x that of the best refined sound fit
            return not (best is not None and passed[e].cost > REFINE_FACTOR * best.cost)

        def hopeful() -> list[tuple]:  # the refinements of passed screens the loop below
            # may run, best first
            won = min(refined(), key=lambda c: c.score, default=None)
            return [refit(e) for e in sorted(passed, key=lambda e: passed[e].cost)
                    if can_win(e, won)]

        held_jobs = [(("screen", e), screened(e)) for e in held]
        # the current model's detailed comparison (the evidence's) while the fits run; the
        # held candidates started on cores the last of them leave idle (dropped if not needed)
        collect(early + [(("screen", e), screened(e)) for e in todo],
                meanwhile=lambda: self._detail(st), spare=held_jobs)
        why = screen.text() if out else linear_explains(
            self.campaign, screen, [(c.cost, c.effect, c.predictions) for c in refined()]
        ) if held else ""
        if held and not why:
            collect(held_jobs)
        elif why:  # not fitted, `why` their evidence
            self.fits.drop_ahead([key for key, _ in held_jobs])
            ranking[:0] = [not_fitted(e, current.with_effect(e), cost, st.err,
                                      st.stages[-1].predictions, self.campaign,
                                      self.table_view, why)
                           for e in sorted(out + held, key=self.catalog.index)]
            done += len(out + held)
        order = sorted(passed, key=lambda e: passed[e].cost)
        # a candidate refined in its screen's task may have won
        best: Candidate | None = min(refined(), key=lambda c: c.score, default=None)
        while order:
            if not can_win(order[0], best):
                break
            batch, order = order[:max(1, self.workers)], order[max(1, self.workers):]
            batch.sort(key=lambda e: -spent.get(e, 0.0))
            for (_, name), fitted in self.fits.dispatch([refit(e) for e in batch],
                                                        ahead=[refit(e) for e in order]):
                c = self._judged(st, name, fitted, spent)
                ranking.append(c)
                progress(done, steps, f"round {k}: tried {name}")
                if admissible(self, c, self.widened) and \
                        (best is None or c.score < best.score):
                    best = c
        self.fits.drop_ahead()  # those started ahead that cannot win: stopped
        for e in order:  # cannot win: kept where their screen left them
            ranking.append(self._judged(
                st, e, passed[e], spent,
                unrefined=f"its training cost after the screen ({passed[e].cost:.4g}) is above "
                          f"{REFINE_FACTOR:g} x that of {best.effect} refined "
                          f"({best.cost:.4g}): not refined further"))
            progress(done, steps, f"round {k}: tried {e}")
        return ranking, left, done

    def _partial(self, st: State) -> Diagnosis:
        """The diagnosis of the rounds that finished, without another simulation."""
        return diagnosis_of(self, st, st.cmp if st.current is not None else None, "",
                            interrupted=True)


def diagnose(runs: Sequence[Run], start_effects: Sequence[str] = (), **kw) -> Diagnosis:
    return Diagnoser(runs, start_effects, **kw).diagnose()
