"""A candidate's fit with the current model's calibration linearised: where to start, and
whether to go on.

A candidate effect is tried on the current model, which is calibrated (its base and effects
fitted: a least-squares minimum). Adding the effect at some values θ_e moves the training
residual from r₀ to r(θ_e); the current parameters b can then move again and take up part
of that (an RC filter the fitted loop had stood in for gives back the loop's departure).
To first order they move by δb = −(JᵀJ)⁻¹Jᵀ r(θ_e), J the current model's Jacobian, and what
is left is the projection of r(θ_e) off J's columns (variable projection: Golub & Pereyra,
SIAM J. Numer. Anal. 10, 1973). So, with J worked out once per round for every candidate
(`Frame`):

1. the effect's values across its range (its grid, its defaults, where an earlier fit of
   it ended) are each simulated once with the current parameters, and scored by the
   projected cost ‖P⊥ r(θ_e)‖² (P⊥ = I − QQᵀ, J = QR);
2. the best is refined in the effect's own parameters on that projected cost (a few
   least-squares steps);
3. a candidate whose projected cost does not fall `SCREEN` (1 %) below the current
   model's cost takes `SCREEN_STEPS` least-squares steps in every parameter from its best
   values with the current parameters moved as the projection says, from its defaults
   with the current parameters, and, when the fitted servo loop is far from the declared
   one, from the loop as declared with the effect at its best there (Broyden's updates
   between steps; one start's Broyden Jacobian carried to the next misled: a platen
   resonator missed). Each start's Jacobian takes, for the parameters the current model
   has, the current model's own (the frame's J for the first two, near the current
   model; for the declared loop's, the current model with its loop as declared,
   linearised once for the round: `Frame.J_declared`), and forward differences for the
   others (the effect's own: one simulation each, not one per parameter). An effect the
   fitted base had absorbed comes back only when both move together, over several steps
   the linearisation cannot see (an RC filter behind friction, entrained air; the
   table's pitch). Still not 1 % below, it is screened out — a gain of 1 % of the
   training cost cannot reach the 5 % of the noise's cost the selection asks
   (criterion 3);
4. otherwise (the gain confirmed by a simulation where the move points: the linearisation
   can promise what the model does not give) every parameter is fitted by least squares,
   this start (the effect's best values, the current parameters moved by δb within their
   bounds) one of the fit's starts (`TableModel`'s `multistart`).

Steps 1-3 run on the first half of each run's training segment (`Campaign.screening`,
`sampling.SCREEN_SHARE`): a gain of 1 % of the training cost shows there as on the whole
segment, at half the simulated time, and a candidate that passes is fitted on the whole
segment (step 4); one screened out has its cost and training error taken on the whole
segment where its steps ended (one simulation). The current model, fitted on the whole
segments, is not at its minimum on the half: its parameters take `BASE_STEPS` there
first (`Frame.of`), and the round's J and the cost a candidate must lower by 1 % are
taken where they end (else every candidate is credited with what the base gains alone:
nine of eleven passed on a yielding building's campaign).

A candidate screened out then costs a few simulations, where a few least-squares steps in
every parameter from each of its starts cost tens of Jacobians. Parameters the
candidate brings that the current model lacks (the platen's pitch inertia and the height of
its centre of mass, when the effect lets it pitch) are held at their starting values in
steps 1-3 and fitted in step 4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

from vtable.diagnose.secant import Secant

#: least-squares steps of the refinement in the effect's own parameters (step 2), and of
#: the steps in every parameter a candidate takes before it is screened out (step 3)
REFINE_STEPS = 3
SCREEN_STEPS = 6
#: least-squares steps the current model's parameters take on the screening share before
#: the round's candidates are screened there (`Frame.of`)
BASE_STEPS = 6
#: the fitted loop this far from the declared one (fitted scale: 0.1 is ~10 %; 4 % air took
#: f_o 43 % down, an RC filter ξ_o 22 %) may stand in for an effect: a candidate is also
#: started from the loop as declared (`TableModel`'s declared start, step 3's third);
#: closer, it has absorbed nothing worth the steps
FAR = 0.1


@dataclass
class Frame:
    """The current model's linearisation on the screening share, shared by a round's
    candidates: its parameters' keys and values (fitted scale) after `BASE_STEPS` there, the
    orthonormal basis Q and triangle R of its Jacobian's data rows (J = QR), and its cost
    there."""

    keys: tuple[str, ...]
    x: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    cost: float
    J: np.ndarray  # the data rows of the Jacobian itself
    #: the data rows of the Jacobian with the loop as declared (the other parameters as
    #: fitted), when the fitted loop is `FAR` from it; else None
    J_declared: np.ndarray | None = None

    @classmethod
    def of(cls, model, physics, campaign) -> Frame:
        """`physics` (the current, fitted model) linearised by forward differences with
        `model` (a `TableModel` on the campaign's table: its layout and residuals) on
        `campaign`'s training targets (a screening campaign's: `Campaign.screening`), and
        its cost there."""
        lay = model._layout(physics)
        x = model._pack(physics, lay)
        lo, hi = model.bounds(lay)
        secant = Secant(lambda z: model._cost(z, physics, lay, campaign), lo, hi,
                        refresh=1 << 30)
        z = np.clip(x, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        J = secant.at(z)
        # fitted on the whole training segments, the current model is not at its minimum on
        # the screening share: its parameters take `BASE_STEPS` there first (Broyden's
        # updates from J), so that no candidate is credited with what they gain alone
        secant.seed(z, J)
        sol = secant.solve(z, bounds=(lo, hi), xtol=1e-6, ftol=1e-8, max_nfev=BASE_STEPS)
        J = J[:campaign.n_target]
        Q, R = scipy.linalg.qr(J, mode="economic")
        return cls(tuple(p.key for p in lay), sol.x, Q, R, float(sol.fun @ sol.fun), J,
                   _declared_jacobian(secant, lay, x, lo, hi, campaign.n_target))

    def project(self, r: np.ndarray) -> np.ndarray:
        """r with what the current parameters take up to first order removed: P⊥ r."""
        return r - self.Q @ (self.Q.T @ r)

    def move(self, r: np.ndarray) -> np.ndarray:
        """The first-order move δb of the current parameters that takes up `r`."""
        c = self.Q.T @ r
        try:
            return -scipy.linalg.solve_triangular(self.R, c, check_finite=False)
        except (np.linalg.LinAlgError, ValueError):
            return -np.linalg.lstsq(self.R, c, rcond=None)[0]


def declared_loop(lay, x: np.ndarray) -> np.ndarray | None:
    """`x` (packed, layout `lay`) with the servo loop's parameters as declared, when the
    fitted loop is `FAR` from them (fitted scale); else None."""
    loop = np.array([p.group == "loop" for p in lay], dtype=bool)
    if not loop.any():
        return None
    declared = np.array([math.log(p.declared) if p.log else p.declared for p in lay])
    if np.max(np.abs(declared - x)[loop]) <= FAR:
        return None
    return np.where(loop, declared, x)


def _declared_jacobian(secant, lay, x: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                       n: int) -> np.ndarray | None:
    """The data rows of the forward-difference Jacobian of the current model with its loop
    as declared (`declared_loop`), or None when its fitted loop is near the declared one:
    every candidate's declared start reads its base columns here (one Jacobian a round,
    not one a candidate)."""
    z = declared_loop(lay, x)
    if z is None:
        return None
    return secant.at(np.clip(z, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo)))[:n]


def projected_start(model, full, start, lay, x0: np.ndarray, frame: Frame,
                    points: list[np.ndarray], idx: list[int], screen: float,
                    declared: np.ndarray | None = None):
    """Steps 1-3 of the module docstring for `model` (a `TableModel` fitting candidate
    `model.multistart` from `start`, layout `lay`, packed `x0`): `points` the effect's
    values to try (fitted scale, at the indices `idx`), `screen` the relative gain it must
    show; `declared`, the start with the servo loop as declared (fitted scale) when the
    fitted loop is far from it. The steps run on the screening share of the training
    campaign `full` (`Campaign.screening`, which `frame` linearises). Returns `model` done
    and screened out (its cost and training error on `full`), or the start of step 4
    (every parameter, fitted scale) for the caller's fit."""
    campaign = full.screening()
    lo, hi = model.bounds(lay)
    n = campaign.n_target
    shared = [(i, frame.keys.index(p.key)) for i, p in enumerate(lay) if p.key in frame.keys]
    ci, fi = (np.array(v, dtype=int) for v in zip(*shared, strict=True)) if shared else \
        (np.zeros(0, dtype=int), np.zeros(0, dtype=int))
    base = x0.copy()
    base[ci] = frame.x[fi]  # the current model's values where the candidate has them
    rest = model._priors(base, lay, campaign)
    rest2 = float(rest @ rest)

    def residual(v: np.ndarray) -> np.ndarray:
        x = base.copy()
        x[idx] = v
        return model._cost(np.clip(x, lo, hi), start, lay, campaign)[:n]

    def projected(v: np.ndarray) -> np.ndarray:
        return frame.project(residual(v))

    best_v, best_c = None, math.inf
    for v in points:
        p = projected(v)
        c = float(p @ p) + rest2
        if c < best_c:
            best_v, best_c = v, c
    eff_lo, eff_hi = lo[idx], hi[idx]
    v0 = np.clip(best_v, eff_lo + 1e-9 * (eff_hi - eff_lo), eff_hi - 1e-9 * (eff_hi - eff_lo))
    sol = scipy.optimize.least_squares(projected, v0, bounds=(eff_lo, eff_hi), diff_step=1e-4,
                                       max_nfev=REFINE_STEPS)
    c = float(sol.fun @ sol.fun) + rest2
    if c < best_c:
        best_v, best_c = sol.x, c
    x = base.copy()
    x[idx] = best_v
    x[ci] += frame.move(residual(best_v))[fi]
    x = np.clip(x, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
    if best_c < frame.cost * (1 - screen):  # the linearised gain, confirmed where it points
        f = model._cost(x, start, lay, campaign)
        if float(f @ f) < frame.cost * (1 - screen):
            return x
    # not yet: a few steps in every parameter from the effect at its defaults and the
    # current parameters (an effect the fitted base absorbed is given back only when both
    # move together, over several steps: the linearised move cannot see it)
    def at_declared() -> np.ndarray:  # the loop as declared, the effect at its best there
        trials = []
        for v in points:
            z = declared.copy()
            z[idx] = v
            f = model._cost(np.clip(z, lo, hi), start, lay, campaign)
            trials.append((float(f @ f), z))
        return min(trials, key=lambda t: t[0])[1]

    # from where the projection points, from the effect's defaults, and from the loop as
    # declared (None: its grid simulated only when the first two did not pass)
    starts = [x, base] + ([None] if declared is not None else [])
    best = None
    others = np.setdiff1d(np.arange(len(x0)), ci)  # the effect's own, and any new ones
    prior_J = _prior_jacobian(model, lay, campaign, x0)[:, ci]  # the priors are linear
    for k, z in enumerate(starts):
        z = np.clip(at_declared() if z is None else z, lo + 1e-9 * (hi - lo),
                    hi - 1e-9 * (hi - lo))
        secant = Secant(lambda q: model._cost(q, start, lay, campaign), lo, hi,
                        refresh=1 << 30)
        base_J = frame.J if k < 2 else frame.J_declared
        if base_J is not None:  # the current model's Jacobian's columns for the parameters
            # it has (near it, or with the loop as declared), forward differences for the
            # effect's own
            J = secant.at(z, others)
            J[:n, ci] = base_J[:, fi]
            J[n:, ci] = prior_J
            secant.seed(z, J)
        sol = secant.solve(z, bounds=(lo, hi), xtol=1e-6, ftol=1e-8, max_nfev=SCREEN_STEPS)
        if float(sol.fun @ sol.fun) < frame.cost * (1 - screen):
            return np.clip(sol.x, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        if best is None or float(sol.fun @ sol.fun) < float(best.fun @ best.fun):
            best = sol
    return model._done(full, start, lay, best.x, model._cost(best.x, start, lay, full), None,
                       screened=True)


def _prior_jacobian(model, lay, campaign, x: np.ndarray) -> np.ndarray:
    """The Jacobian of the calibration's prior rows (linear in x: forward differences of
    the priors alone cost no simulation)."""
    p0 = model._priors(x, lay, campaign)
    J = np.empty((len(p0), len(x)))
    for i in range(len(x)):
        z = x.copy()
        z[i] += 1.0
        J[:, i] = model._priors(z, lay, campaign) - p0
    return J
