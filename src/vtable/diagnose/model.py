"""`TableModel`: a scikit-learn-style estimator over the reduced model — the primitive the
diagnosis loop is built from.

`TableModel(effects).fit(runs)` fits the calibrated base (`vtable.diagnose.calibration`:
the servo loop (f_o, ξ_o, k_o), the specimen's modal frequencies, damping and mass, the
platen's mass, and its centre-of-mass height and pitch inertia when the model pitches;
bounded around the runs' declarations, with weak priors) and the effects' parameters by
bounded least squares on the training segments of the campaign (the first 60 % of every
run, at most its first 30 s, at the analysis rate), on the fitted scale (logarithmic for
log parameters); `score` / `comparison` evaluate the held-out segments; `predictions`
keeps what the fitted model predicts for every run of the campaign. `flags_` says which
fitted parameters sit at a bound and which effect parameters the data cannot tell apart
from the base.
"""

from __future__ import annotations

import functools
import math
import threading
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import scipy.optimize
from threadpoolctl import ThreadpoolController

from vtable.diagnose.calibration import LOOP, Calibration
from vtable.diagnose.campaign import Campaign
from vtable.diagnose.choices import fit_choices
from vtable.diagnose.compare import Comparison, compare
from vtable.diagnose.evidence import started
from vtable.diagnose.layout import with_states
from vtable.diagnose.projected import Frame, declared_loop, projected_start
from vtable.diagnose.residuals import Residuals
from vtable.diagnose.reuse import model_at
from vtable.diagnose.secant import REFRESH, Families, Secant
from vtable.diagnose.statistics import correlations
from vtable.effects.registry import get as effect
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.runs.model import Run

AT_BOUND = 0.01  # a fitted value within 1 % of its range (fitted scale) of a bound is flagged
#: an effect parameter this correlated with a base parameter is not identifiable apart
#: from the base (the fit could trade one for the other)
MAX_CORRELATION = 0.95
SCREEN = 0.01  # a candidate must lower the training cost by 1 % in its first steps ...
#: ... and one whose screen halves it is refined at once (it is likely to win its round)
STRONG = 0.5
SCREEN_STEPS = 3  # ... (least-squares iterations from the best start) to be refined further
#: the base loop's fitted parameters: name -> (JSON key "owner.param", unit, lower, upper)
BASE_PARAMS = LOOP
MULTISTART = (0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95, None)  # fractions of a range; None: as is
RIVAL = 10.0  # base starts whose refined grid cost is within this factor of the best go on
#: least-squares iterations from a start with the effect at its defaults before the rivals
#: are compared: such a start's base has absorbed part of the effect, and the first steps
#: give it back (an RC filter behind friction: 0.043 after 3, 0.00105 after 5)
AS_IS_STEPS = 2 * SCREEN_STEPS
#: ... and from the best grid start with the loop as declared: entrained air that the fitted
#: loop stood in for, and Table B.5's RC filter behind it, step back from there (a README
#: campaign with 4 % air: 0.0102 after 6, 0.0087 after 10, against 0.0096 without the
#: filter), when the fitted loop is `projected.FAR` from the declared one
DECLARED_STEPS = 10
#: the last least-squares run of a fit (forward differences at every step) ends at a step
#: that lowers the cost by less than this share of it (1e-4 flipped a real run's mount for
#: a filter; 1e-8 spent a tenth of the run's steps on the last 1e-6)
FINAL_FTOL = 1e-6
#: a backward step's refit (the model without one effect) whose first `SCREEN_STEPS` leave
#: its training cost above this many times the model's is not refined: keeping the effect
#: is a gain (the scorecard's 12 backward refits: the screened cost within 1.3 x the
#: refined one, every refined one 3.5 x the model's or more; the README campaign's 70 to
#: 1,400 x)
BACKWARD_FACTOR = 10.0


@functools.cache
def _blas() -> ThreadpoolController:
    return ThreadpoolController()


def one_blas_thread():
    """A context in which BLAS runs on one thread: a fit's matrices are small, and the
    threads' start costs more than they save (the libraries looked up once per process:
    each look is ~3 ms, once per fit it was)."""
    return _blas().limit(limits=1, user_api="blas")


class TableModel(Residuals):
    """The linear uni-directional servo loop carrying the runs' specimen (report ch. 7)
    plus `effects`, with the base calibrated around the runs' declarations
    (`vtable.diagnose.calibration`).

    Parameters
    ----------
    effects
        Effect names (the registry's) in the model, at their defaults to start with.
    start
        A `Physics` to start from instead (its effects and values); `effects` are added.
    multistart
        An effect whose parameters start from the best of a few values across their
        bounds, with the start's base loop and the nominal one (threshold effects, and
        effects a refitted base loop had absorbed, need it); and, whatever their cost,
        from the effect at its defaults with the base as fitted (`AS_IS_STEPS` steps in
        every parameter) and from its best grid start with the loop as declared
        (`DECLARED_STEPS`): an earlier fit's base that absorbed part of the effect gives
        it back only so. Its discrete parameters are chosen (`Effect.choices`), the other
        effects' kept as `start` has them.
    stop
        A `threading.Event`; when set, the fit ends at its next simulation
        (`StopRequestedError`).
    calibration
        The calibration's bounds and priors (default `Calibration()`).
    baseline
        The training cost (sum of squared residuals and priors) of the model without the
        `multistart` effect: when `SCREEN_STEPS` least-squares iterations from the best
        grid start (and the steps from the two starts above) do not lower it by `SCREEN`
        (a relative 1 %), the fit stops there and `screened_` is set (the diagnosis's
        screening of candidates: such a fit cannot clear the selection margin).
    seed
        The `multistart` effect's parameters where an earlier fit of it ended (its units):
        one more start (the diagnosis passes the previous round's).
    frame
        The current model's linearisation (`vtable.diagnose.projected.Frame`): with a
        `baseline`, the `multistart` effect is screened on the projected cost
        (`projected.projected_start`), which also gives its fit one more start.
    screen_only
        Stop where a screen that passed stopped (`passed_`: the fitted-scale vector, the
        model done there unrefined; the diagnosis refines the candidates that can still
        win, `begin`), unless the screen's point costs less than `STRONG` times the
        baseline: such a candidate is refined at once.
    begin
        The fitted-scale vector a screen that passed stopped at (`passed_`): the fit's
        projected start, the screen not run again.
    choose
        Without a `multistart` effect, whose discrete parameters the fit chooses
        (`Effect.choices`: which storey yields): every effect's (True), none (False: a
        refit of a fitted model, whose choices were made when its effects were added;
        `start`'s are kept), or those of the effects named (the ones a refit adds).
    ceiling
        Without a `multistart` effect or a `baseline`: a training cost `SCREEN_STEPS`
        least-squares iterations must bring the fit under, or it stops there, screened (a
        backward step's refit, `refit_without`); under it, the fit runs from its start as
        without a ceiling.
    """

    def __init__(self, effects: Sequence[str] = (), *, start: Physics | None = None,
                 multistart: str | None = None, stop: threading.Event | None = None,
                 calibration: Calibration | None = None,
                 baseline: float | None = None, seed: dict[str, float] | None = None,
                 frame: Frame | None = None, screen_only: bool = False,
                 begin: np.ndarray | None = None,
                 choose: bool | Sequence[str] = True, ceiling: float | None = None) -> None:
        self.effects = tuple(effects)
        self.ceiling = ceiling
        self.choose = choose
        self.frame, self.screen_only, self.begin = frame, screen_only, begin
        self.passed_: np.ndarray | None = None  # where a screen that passed stopped
        self.start, self.multistart, self.stop = start, multistart, stop
        self.seed = seed
        self.calibration = calibration or Calibration()
        self.baseline = baseline
        self.clear_caches()
        self.screened_ = False
        self.physics_: Physics | None = None
        self.vt = None  # the campaign's table, known when fitting
        self.declared = None  # the campaign's declared specimen, known when fitting
        self.state_specimens: dict = {}  # further states -> their declared specimen
        self.campaign_: Campaign | None = None
        self.start_notes_: list[str] = []

    @classmethod
    def unfitted(cls, campaign: Campaign, calibration: Calibration | None = None,
                 stop: threading.Event | None = None) -> TableModel:
        """An estimator on `campaign`'s table and declaration, not fitted: its layout,
        residuals and tables of the base (`calibration`'s bounds) for models it is given
        (a diagnosis's `Frame`, `at_bounds`, `base_table`)."""
        m = cls(stop=stop, calibration=calibration)
        m.vt, m.declared = campaign.table, campaign.specimen
        m.state_specimens, m.campaign_ = campaign.state_specimens, campaign
        return m

    def frame_of(self, physics: Physics, campaign: Campaign) -> Frame:
        """The linearisation of `physics` (a fitted model) a diagnosis's next round
        screens its candidates on (`projected.Frame`), on `campaign`'s screening share of
        the window `physics` trains on."""
        with one_blas_thread():
            return Frame.of(self, physics, campaign.training_for(physics).screening())

    # -- the estimator -----------------------------------------------------------------
    def fit(self, runs: Sequence[Run] | Campaign) -> TableModel:
        """Fit on the campaign's training segments. Sets `physics_`, `train_error_`
        (RMS over the groups of the normalised training residual), `flags_` (fitted
        parameters at a bound, effect parameters not identifiable apart from the base),
        `base_` (the spec's `base` table), `notes_`."""
        with one_blas_thread():
            return self._fit(Campaign.of(runs))

    def at(self, runs: Sequence[Run] | Campaign, values: Mapping[str, float],
           source: str = "values") -> TableModel:
        """The model at given values of every calibrated parameter, not fitted
        (`vtable.diagnose.reuse.model_at`: a diagnosis's, for `vtable drive --from`)."""
        return model_at(self, Campaign.of(runs), values, source)

    def _fit(self, campaign: Campaign) -> TableModel:
        self.vt = campaign.table
        self.declared = campaign.specimen
        self.state_specimens = campaign.state_specimens
        start = with_states(self.start or Physics(nominal_open_loop(self.vt),
                                                  campaign.specimen, {}), campaign)
        self.start_notes_ = []  # what the runs show of the effects it adds (`started`)
        start = started(start, self.effects, campaign, self.start_notes_)
        campaign = campaign.training_for(start)
        self.campaign_ = campaign
        # the whole values chosen: the candidate's own when there is one (the model it
        # joins chose its own when they were added), else every effect's unless kept
        choose = {self.multistart} if self.multistart else set(start.effects) \
            if self.choose is True else set(self.choose or ())
        choices = [(name, p) for name in start.effects for p in effect(name).params
                   if p.discrete and name in choose]
        if not choices:
            return self._fit_from(campaign, start)
        return self._fit_choices(campaign, start, choices)

    def _fit_choices(self, campaign: Campaign, start: Physics, choices) -> TableModel:
        """Fit once for every combination of the discrete parameters' whole values the
        effects propose, keeping the lowest training cost (`choices.fit_choices`)."""
        return fit_choices(self, campaign, start, choices)

    def _fit_from(self, campaign: Campaign, start: Physics) -> TableModel:
        """The fit from `start` (its discrete parameters as they are)."""
        self.start_ = start
        lay = self._layout(start)
        x0 = self._pack(start, lay)
        if self.multistart:
            idx = [i for i, p in enumerate(lay) if p.group == f"effect:{self.multistart}"]
            base = [i for i, p in enumerate(lay) if p.group != f"effect:{self.multistart}"]
            # the start's base and effects (fitted before this effect was there, they may
            # have absorbed some of it), and the same with the declared loop (an effect of
            # the servo loop that the fitted loop absorbed)
            declared = np.array([math.log(lay[i].declared) if lay[i].log else lay[i].declared
                                 for i in base])
            loop = np.array([lay[i].group == "loop" for i in base])
            mixed = np.where(loop, declared, x0[base])
            points = []  # the effect's parameters across their ranges (fitted scale) ...
            for frac in MULTISTART:
                v = x0[idx].copy()
                if frac is not None:
                    for k, i in enumerate(idx):
                        p = lay[i]
                        a, b = ((math.log(p.lower), math.log(p.upper)) if p.log
                                else (p.lower, p.upper))
                        v[k] = a + frac * (b - a)
                points.append(v)
            names = [lay[i].key.split(".", 1)[1] for i in idx]
            if self.seed and set(names) & set(self.seed):  # ... and where an earlier fit of
                v = x0[idx].copy()  # it ended (or what the runs show of it: the rest as it
                for k, (i, name) in enumerate(zip(idx, names, strict=True)):  # starts)
                    if name in self.seed:
                        v[k] = math.log(self.seed[name]) if lay[i].log else self.seed[name]
                points.append(v)
            near = not loop.any() or np.max(np.abs(mixed - x0[base])[loop]) < 0.02
            declared_x = declared_loop(lay, x0)  # the loop as declared, when `FAR` from it
            projected = self.begin
            if projected is None and self.frame is not None and self.baseline is not None:
                projected = projected_start(self, campaign, start, lay, x0, self.frame,
                                            points, idx, SCREEN, declared_x)
                if projected is self:  # screened out on the projected cost
                    return self
                f = self._cost(projected, start, lay, campaign)
                if self.screen_only and float(f @ f) > STRONG * self.baseline:
                    self.passed_ = projected  # the diagnosis decides whether to refine it
                    return self._done(campaign, start, lay, projected, f, None)
            starts: list[tuple[float, np.ndarray]] = []  # the best of each base start
            # (a fitted loop within 2 % of the declared one is a start of its own already)
            bases = (x0[base],) if near else (x0[base], mixed)
            for base_x in bases:
                best, best_x = np.inf, x0
                for v in points:
                    x = x0.copy()
                    x[base] = base_x
                    x[idx] = v
                    c = float(np.sum(self._cost(x, start, lay, campaign) ** 2))
                    if c < best:
                        best, best_x = c, x
                starts.append((best, best_x))
        lo, hi = self.bounds(lay)
        if self.multistart:
            # a grid on the effect alone is coarse (an effect the loop absorbed has a sharp
            # valley across it): each base start's best grid point is refined in the
            # effect's own parameters, and every one that comes within RIVAL x the best
            # gets a few least-squares steps in all parameters before one wins
            eff = np.zeros(len(lay), dtype=bool)
            eff[idx] = True
            grid = [x for _, x in starts]
            starts = [self._refine(x, eff, lo, hi, start, lay, campaign) for _, x in starts]
            c_min = min(c for c, _ in starts)
            rivals = [(x, SCREEN_STEPS) for c, x in sorted(starts, key=lambda s: s[0])
                      if c <= RIVAL * c_min]
            # and two starts whatever their cost before their steps in every parameter:
            # where an earlier fit's base absorbed part of the effect (a free loop taking
            # up an RC filter or entrained air), the effect refined with the base held
            # slides off towards "absent", and only steps in every parameter find it:
            # the effect at its defaults with the base as fitted, and with the loop as
            # declared the best of its grid (its defaults among them: an effect the
            # fitted loop stood in for must take up the whole departure at once)
            if projected is not None:  # it passed the projected screen: fitted in full,
                rivals.append((projected, SCREEN_STEPS))  # from its projected start too
            elif self.baseline is not None:  # a screened (costly) candidate: the best start
                rivals = rivals[:1]
            rivals.append((x0.copy(), AS_IS_STEPS))
            if declared_x is not None:  # an effect the fitted loop absorbed
                rivals.append((grid[-1], DECLARED_STEPS))
            x0 = min(starts, key=lambda s: s[0])[1]
        else:
            rivals = []

        def solve(x, nfev, refresh=REFRESH, ftol=1e-8, families=None):
            as_declared = families is not None and np.allclose(x[base][loop], declared[loop])
            x = np.clip(x, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
            secant = Secant(lambda x: self._cost(x, start, lay, campaign), lo, hi,
                            refresh=refresh)
            if families is not None:  # a rival: its loop's family's Jacobian
                families.seed(secant, x, as_declared)
            sol = secant.solve(x, bounds=(lo, hi), xtol=1e-6, ftol=ftol, max_nfev=nfev)
            sol.secant = secant
            return sol

        if len(rivals) > 1 and self.baseline is not None and projected is None:
            # screening: `SCREEN_STEPS` from every rival first; only a candidate that lowers
            # the cost by `SCREEN` there has its longer starts run to the end
            shared = Families(idx)
            first = [(solve(x, min(n, SCREEN_STEPS), families=shared), n) for x, n in rivals]
            sol = min((f for f, _ in first), key=lambda s: float(np.sum(s.fun**2)))
            if float(np.sum(sol.fun**2)) >= self.baseline * (1 - SCREEN):
                return self._done(campaign, start, lay, sol.x, sol.fun, sol.jac, screened=True)
            sol = min([f if n <= SCREEN_STEPS else solve(f.x, n - SCREEN_STEPS)
                       for f, n in first], key=lambda s: float(np.sum(s.fun**2)))
            x0 = sol.x
        elif len(rivals) > 1:  # a few steps from each rival; the best goes on
            shared = Families(idx)
            sol = min((solve(x, n, families=shared) for x, n in rivals),
                      key=lambda s: float(np.sum(s.fun**2)))
            x0 = sol.x
        elif self.baseline is not None:  # screening: a few steps first
            sol = solve(x0, SCREEN_STEPS)
            if float(np.sum(sol.fun**2)) >= self.baseline * (1 - SCREEN):
                return self._done(campaign, start, lay, sol.x, sol.fun, sol.jac, screened=True)
            x0 = sol.x
        elif self.ceiling is not None:  # a backward refit: a few steps first; from its
            sol = solve(x0, SCREEN_STEPS)  # start again if they leave it below the ceiling
            if float(np.sum(sol.fun**2)) > self.ceiling:
                return self._done(campaign, start, lay, sol.x, sol.fun, sol.jac, screened=True)
        # the best start goes on with forward-difference Jacobians (Broyden's may stop
        # short of the minimum: a pitch fit ten times the cost it can reach), the last of
        # them the covariance the flags read
        sol = solve(x0, 40, refresh=1, ftol=FINAL_FTOL)
        return self._done(campaign, start, lay, sol.x, sol.fun, sol.secant.at_end(sol.x))

    def _refine(self, x: np.ndarray, eff: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                start: Physics, lay, campaign: Campaign) -> tuple[float, np.ndarray]:
        """A few least-squares steps in the parameters `eff` only, the rest held at `x`:
        (cost, the refined x)."""
        x = np.clip(x, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))

        def cost(xe):
            z = x.copy()
            z[eff] = xe
            return self._cost(z, start, lay, campaign)

        sol = scipy.optimize.least_squares(cost, x[eff], bounds=(lo[eff], hi[eff]),
                                           diff_step=1e-4, max_nfev=SCREEN_STEPS)
        z = x.copy()
        z[eff] = sol.x
        return float(np.sum(sol.fun**2)), z

    def _done(self, campaign: Campaign, start: Physics, lay, x, fun, jac,
              screened: bool = False) -> TableModel:
        self.physics_ = self._unpack(x, start, lay)
        n_data = campaign.n_target
        self.cost_ = float(np.sum(fun**2))
        self.train_error_ = float(np.sqrt(np.sum(fun[:n_data] ** 2) / len(campaign.targets)))
        self.layout_ = lay
        self.screened_ = screened
        if screened or jac is None:  # not refined: no covariance at a solution
            self.correlations_ = np.full((len(lay), len(lay)), np.nan)
            self.flags_ = [] if screened else self.at_bounds(self.physics_)
        else:
            self.correlations_ = correlations(jac, len(lay))
            self.flags_ = self.at_bounds(self.physics_) + self._unidentified(lay)
        self.base_ = self.base_table(self.physics_)
        self.notes_ = list(dict.fromkeys([*campaign.notes, *self.start_notes_]))
        return self

    def _unidentified(self, lay) -> list[str]:
        """Effect parameters the fit cannot tell apart from a base parameter (|correlation|
        above `MAX_CORRELATION` in the Gauss-Newton covariance at the solution)."""
        R = self.correlations_
        flags = []
        for i, p in enumerate(lay):
            if not p.group.startswith("effect:"):
                continue
            if not np.isfinite(R[i, i]):
                flags.append(f"{p.key} not identifiable (the data do not depend on it)")
                continue
            for j, b in enumerate(lay):
                if not p.group.startswith("effect:") and abs(R[i, j]) > MAX_CORRELATION:
                    flags.append(f"{p.key} not identifiable apart from {b.key} "
                                 f"(correlation {R[i, j]:+.2f})")
                    break
        return flags

    def predictions(self, campaign: Campaign | None = None) -> dict[str, dict[str, np.ndarray]]:
        """The fitted model's channels for every run of the campaign (analysis rate)."""
        return self._predict(self.physics_, campaign or self.campaign_)

    def comparison(self, runs: Sequence[Run] | Campaign | None = None, detail: bool = True,
                   predictions: dict | None = None) -> Comparison:
        """Held-out errors of the fitted model (with `detail`: bands, amplitudes, windows)."""
        c = self.campaign_ if runs is None else Campaign.of(runs)
        pred = predictions if predictions is not None else self.predictions(c)
        return compare(pred, c.runs, scored="held", floor=c.floor, detail=detail)

    def score(self, runs: Sequence[Run] | Campaign | None = None) -> float:
        return self.comparison(runs, detail=False).error

    def predict(self, run: Run) -> dict[str, np.ndarray]:
        """The run's predictable channels (SI) at the run's own sample rate (in its
        specimen state, when the campaign the model was fitted on has several)."""
        state = self.campaign_.state(run) if self.campaign_ is not None else run.state
        return ReducedModel(self.physics_.in_state(state), self.vt).predict(run)

    # -- what the fit says about itself --------------------------------------------------
    def at_bounds(self, ph: Physics) -> list[str]:
        """The fitted parameters of `ph` within 1 % of a bound, on the fitted scale (the
        logarithm for log parameters): 'owner.param at its lower bound (value unit)'."""
        flags = []
        for p in self._layout(ph):
            v = p.get(ph)
            f = math.log if p.log else (lambda z: z)
            pos = (f(v) - f(p.lower)) / (f(p.upper) - f(p.lower))
            for side, bound, near in (("lower", p.lower, pos <= AT_BOUND),
                                      ("upper", p.upper, pos >= 1 - AT_BOUND)):
                if near:
                    u = "" if p.unit == "1" else f" {p.unit}"
                    flags.append(f"{p.key} at its {side} bound ({v:.4g}{u}; bound {bound:g}{u})")
        return flags

    def base_table(self, ph: Physics) -> dict[str, dict[str, Any]]:
        """The spec's `base`: every calibrated base parameter, "owner.param" ->
        {declared, fitted, bounds, unit, prior}. The servo loop's declared value is the
        table's nominal loop (its constants through eq 6.16)."""
        return {p.key: {"declared": p.declared, "fitted": p.get(ph),
                        "bounds": [p.lower, p.upper], "unit": p.unit,
                        "prior": ("none" if not p.prior else
                                  f"±{p.prior:.3g}{'' if p.log else ' ' + p.unit}"
                                  + (" (log)" if p.log else ""))}
                for p in self.base_params(ph)}


def refit_without(current: Physics, name: str, cost: float | None = None,
                  campaign: Campaign | None = None) -> dict[str, Any]:
    """The keywords of a backward step's refit: the fitted model `current` without the
    effect `name`, the others' discrete choices kept (`TableModel`'s `choose`); given the
    training `cost` of `current` on `campaign`, under a `ceiling` of `BACKWARD_FACTOR`
    times it where both models train on the same window (not when `name` is what
    accumulates over a run: `Campaign.apart`)."""
    job: dict[str, Any] = {"start": current.without(name), "choose": False}
    if cost is not None and campaign is not None and not campaign.apart(job["start"], current):
        job["ceiling"] = BACKWARD_FACTOR * cost
    return job
