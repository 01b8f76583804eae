"""What a `TableModel` fit minimises: the reduced model of a `Physics` simulated on a
campaign's training segments (`_train_outputs`: only the channels and samples the targets
need), the targets' normalised residuals (`_residuals`), and the calibration's priors
beside them (`_cost`). The last `COSTS_KEPT` residual vectors are kept: a point a fit asks
again (a least-squares run starting where the last ended, a screen's start confirmed and
then fitted from) is not simulated again (8 % of a README campaign's evaluations with 16
kept; with 16, a winner's fit still simulated 3-5 % of its points twice, its forward
differences having pushed them out).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

import numpy as np

from vtable.diagnose.campaign import Campaign
from vtable.diagnose.layout import Layout
from vtable.errors import VtableError
from vtable.models.physics import Physics
from vtable.models.reduced import ReducedModel
from vtable.runs.model import Run

#: residual vectors a fit keeps, so that a point asked again is not simulated again
COSTS_KEPT = 64  # ~10 MB on a README campaign's training rows


class StopRequestedError(Exception):
    """Raised inside a fit when the caller asked it to stop (an interrupt)."""


class Residuals(Layout):
    """The simulation and residuals of `TableModel` (its base): reads its `stop` flag and
    `vt`; owns the caches (`clear_caches`)."""

    def clear_caches(self) -> None:
        """No command, residual vector or unpacked point kept: `_commands` ((run, samples)
        -> the command), `_costs` (at most `COSTS_KEPT` of (start, layout, campaign, x,
        residuals)), `_last` (`Layout._unpack_fast`'s)."""
        self._commands: dict = {}
        self._costs: deque = deque(maxlen=COSTS_KEPT)
        self._last = None

    def _models(self, ph: Physics, campaign: Campaign) -> Callable[[Run], ReducedModel]:
        """The reduced model of each run: `ph` in the run's specimen state
        (`Campaign.state`), built once per state."""
        vt, built = self.vt or campaign.table, {}

        def of(run: Run) -> ReducedModel:
            s = campaign.state(run)
            if s not in built:
                built[s] = ReducedModel(ph.in_state(s), vt)
            return built[s]

        return of

    def _predict(self, ph: Physics, campaign: Campaign, train_only: bool = False
                 ) -> dict[str, dict[str, np.ndarray]]:
        model = self._models(ph, campaign)
        out = {}
        for r in campaign.runs:
            if self.stop is not None and self.stop.is_set():
                raise StopRequestedError
            n = campaign.train_stop(r) if train_only else len(r.time)
            key = (r.name, n)
            if key not in self._commands:  # one array per segment: its interpolation is kept
                self._commands[key] = (r.time[:n], r.channel("h_span")[:n])
            out[r.name] = model(r).simulate(*self._commands[key])
        return out

    def _train_outputs(self, ph: Physics, campaign: Campaign
                       ) -> dict[str, dict[str, np.ndarray]]:
        """The channels the training targets need, at their samples (every other one of
        each run's training segment: `Campaign.targets`), of the model `ph`
        (`ReducedModel.outputs`)."""
        model = self._models(ph, campaign)
        out = {}
        for r, names in campaign.target_channels:
            if self.stop is not None and self.stop.is_set():
                raise StopRequestedError
            n = campaign.train_stop(r)
            key = (r.name, n)
            if key not in self._commands:  # one array per segment: its interpolation is kept
                self._commands[key] = (r.time[:n], r.channel("h_span")[:n])
            out[r.name] = model(r).outputs(*self._commands[key], names, step=2)
        return out

    def _residuals(self, ph: Physics, campaign: Campaign) -> np.ndarray:
        try:
            pred = self._train_outputs(ph, campaign)
        except VtableError:
            return np.full(campaign.n_target, 10.0)
        out = np.empty(campaign.n_target)
        k = 0
        for (r, _, y, _), chans in zip(campaign.targets, campaign.target_groups, strict=True):
            p = pred[r.name]
            arrays = [p[c] for c in chans if c in p]
            out[k:k + len(y)] = arrays[0] if all(a is arrays[0] for a in arrays) \
                else np.mean(arrays, axis=0)
            k += len(y)
        y, scale, fill = campaign.target_vectors
        out -= y
        out *= scale
        bad = ~np.isfinite(out)
        if bad.any():
            out[bad] = fill[bad]
        return out

    def _cost(self, x, start, lay, campaign) -> np.ndarray:
        """The residual vector (training data rows, then the calibration's priors) at the
        packed parameters `x` of layout `lay` from `start`; a point kept (the module
        docstring) is not simulated again."""
        key = np.asarray(x, dtype=float).tobytes()
        for s, lo, c, k, f in self._costs:
            if k == key and s is start and lo is lay and c is campaign:
                return f.copy()
        f = np.concatenate([self._residuals(self._unpack_fast(x, start, lay), campaign),
                            self._priors(x, lay, campaign)])
        self._costs.append((start, lay, campaign, key, f.copy()))
        return f
