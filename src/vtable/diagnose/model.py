"""`TableModel`: a scikit-learn-style estimator over the reduced model — the primitive the
diagnosis loop is built from.

`TableModel(effects).fit(runs)` fits the base loop (f_o, ξ_o, k_o) and the effects'
parameters by bounded least squares on the training segments of the campaign (the first
60 % of every run, at the analysis rate), on the fitted scale (logarithmic for log
parameters); `score` / `comparison` evaluate the held-out segments; `predictions` keeps
what the fitted model predicts for every run of the campaign.
"""

from __future__ import annotations

import dataclasses
import math
import threading
from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.optimize

from vtable.diagnose.campaign import Campaign
from vtable.diagnose.compare import Comparison, compare, group_prediction, segments
from vtable.effects.physics import Physics, nominal_open_loop
from vtable.effects.reduced import ReducedModel
from vtable.effects.registry import get as effect
from vtable.errors import VtableError
from vtable.params.loops import OpenLoop
from vtable.params.virtual import virtual_table
from vtable.runs.model import Run

AT_BOUND = 0.01  # a fitted value within 1 % of its range (fitted scale) of a bound is flagged
#: the base loop's fitted parameters: name -> (JSON key "owner.param", unit, lower, upper)
BASE_PARAMS = {"f_o": ("servo_loop.f_o_hz", "Hz", 1.0, 100.0),
               "xi_o": ("servo_loop.xi_o", "1", 0.02, 5.0),
               "k_o": ("servo_loop.k_o_per_s", "1/s", 1.0, 500.0)}
MULTISTART = (0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95, None)  # fractions of a range; None: as is


class StopRequestedError(Exception):
    """Raised inside a fit when the caller asked it to stop (an interrupt)."""


class TableModel:
    """The linear uni-directional servo loop carrying the runs' specimen (report ch. 7)
    plus `effects`.

    Parameters
    ----------
    effects
        Effect names (the registry's) in the model, at their defaults to start with.
    start
        A `Physics` to start from instead (its effects and values); `effects` are added.
    multistart
        An effect whose parameters start from the best of a few values across their
        bounds, with the start's base loop and the nominal one (threshold effects, and
        effects a refitted base loop had absorbed, need it).
    stop
        A `threading.Event`; when set, the fit ends at its next simulation
        (`StopRequestedError`).
    """

    def __init__(self, effects: Sequence[str] = (), *, start: Physics | None = None,
                 multistart: str | None = None, stop: threading.Event | None = None) -> None:
        self.effects = tuple(effects)
        self.start, self.multistart, self.stop = start, multistart, stop
        self.physics_: Physics | None = None
        self.vt = None  # the campaign's table, known when fitting

    # -- parameter vector --------------------------------------------------------------
    def _layout(self, ph: Physics) -> list[tuple[str, str, float, float, bool]]:
        lay = [("base", n, lo, hi, True) for n, (_, _, lo, hi) in BASE_PARAMS.items()]
        for name in ph.effects:
            for p in effect(name).params:
                lay.append((name, p.name, p.lower, p.upper, p.log))
        return lay

    @staticmethod
    def _value(ph: Physics, owner: str, name: str) -> float:
        return getattr(ph.open_loop, name) if owner == "base" else ph.effects[owner][name]

    def _pack(self, ph: Physics, lay) -> np.ndarray:
        return np.array([math.log(self._value(ph, o, n)) if log else self._value(ph, o, n)
                         for o, n, _, _, log in lay])

    @staticmethod
    def _unpack(x: np.ndarray, ph: Physics, lay) -> Physics:
        base = {}
        eff = {k: dict(v) for k, v in ph.effects.items()}
        for xi, (owner, name, lo, hi, log) in zip(x, lay, strict=True):
            v = float(np.clip(math.exp(xi) if log else xi, lo, hi))
            if owner == "base":
                base[name] = v
            else:
                eff[owner][name] = v
        return dataclasses.replace(ph, open_loop=OpenLoop(**base), effects=eff)

    # -- simulate ----------------------------------------------------------------------
    def _predict(self, ph: Physics, campaign: Campaign, train_only: bool = False
                 ) -> dict[str, dict[str, np.ndarray]]:
        model = ReducedModel(ph, self.vt or campaign.table)
        out = {}
        for r in campaign.runs:
            if self.stop is not None and self.stop.is_set():
                raise StopRequestedError
            n = segments(r)[0].stop if train_only else len(r.time)
            out[r.name] = model.simulate(r.time[:n], r.channel("h_span")[:n])
        return out

    def _residuals(self, ph: Physics, campaign: Campaign) -> np.ndarray:
        try:
            pred = self._predict(ph, campaign, train_only=True)
        except VtableError:
            return np.full(campaign.n_target, 10.0)
        res = []
        for r, g, y, norm in campaign.targets:
            yhat = group_prediction(pred[r.name], r, g)[: segments(r)[0].stop][::2]
            e = (yhat - y) / norm
            res.append(np.where(np.isfinite(e), e, 10.0 / math.sqrt(len(e))))
        return np.concatenate(res)

    # -- the estimator -----------------------------------------------------------------
    def fit(self, runs: Sequence[Run] | Campaign) -> TableModel:
        """Fit on the campaign's training segments. Sets `physics_`, `train_error_`
        (RMS over the groups of the normalised training residual), `flags_` (fitted
        parameters at a bound), `base_` (the spec's `base` table), `notes_`."""
        campaign = Campaign.of(runs)
        self.campaign_ = campaign
        self.vt = campaign.table
        start = self.start or Physics(nominal_open_loop(self.vt), campaign.specimen, {})
        for e in self.effects:
            if not start.has(e):
                start = start.with_effect(e)
        self.start_ = start
        lay = self._layout(start)
        x0 = self._pack(start, lay)
        nb = len(BASE_PARAMS)
        if self.multistart:
            idx = [i for i, (o, *_rest) in enumerate(lay) if o == self.multistart]
            nominal = self._pack(dataclasses.replace(
                start, open_loop=nominal_open_loop(self.vt)), lay)
            best, best_x = np.inf, x0
            for base in (x0[:nb], nominal[:nb]):
                for frac in MULTISTART:
                    x = x0.copy()
                    x[:nb] = base
                    for i in idx:
                        _, _, lo, hi, log = lay[i]
                        if frac is not None:
                            a, b = (math.log(lo), math.log(hi)) if log else (lo, hi)
                            x[i] = a + frac * (b - a)
                    c = float(np.sum(self._residuals(self._unpack(x, start, lay),
                                                     campaign) ** 2))
                    if c < best:
                        best, best_x = c, x
            x0 = best_x
        lo = np.array([math.log(a) if log else a for _, _, a, _, log in lay])
        hi = np.array([math.log(b) if log else b for _, _, _, b, log in lay])
        x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
        sol = scipy.optimize.least_squares(
            lambda x: self._residuals(self._unpack(x, start, lay), campaign), x0,
            bounds=(lo, hi), diff_step=1e-4, xtol=1e-6, ftol=1e-8, max_nfev=40)
        self.physics_ = self._unpack(sol.x, start, lay)
        self.train_error_ = float(np.sqrt(np.mean(sol.fun**2) * len(sol.fun)
                                          / len(campaign.targets)))
        self.flags_ = self.at_bounds(self.physics_)
        self.base_ = self.base_table(self.physics_)
        self.notes_ = list(campaign.notes)
        return self

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
        """The run's predictable channels (SI) at the run's own sample rate."""
        return ReducedModel(self.physics_, self.vt).predict(run)

    # -- what the fit says about itself --------------------------------------------------
    def at_bounds(self, ph: Physics) -> list[str]:
        """The fitted parameters of `ph` within 1 % of a bound, on the fitted scale (the
        logarithm for log parameters): 'owner.param at its lower bound (value unit)'."""
        flags = []
        for owner, name, lo, hi, log in self._layout(ph):
            v = self._value(ph, owner, name)
            if owner == "base":
                key, unit = BASE_PARAMS[name][:2]
            else:
                key, unit = f"{owner}.{name}", effect(owner).param(name).unit
            f = math.log if log else (lambda z: z)
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
        nominal = nominal_open_loop(self.vt or virtual_table())
        return {key: {"declared": getattr(nominal, n), "fitted": getattr(ph.open_loop, n),
                      "bounds": [lo, hi], "unit": unit}
                for n, (key, unit, lo, hi) in BASE_PARAMS.items()}
