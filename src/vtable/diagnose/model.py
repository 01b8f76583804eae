"""A scikit-learn-style estimator over the reduced model: fit on runs, score, predict."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vtable.diagnose.compare import Comparison
from vtable.diagnose.engine import Diagnoser
from vtable.effects.physics import Physics
from vtable.effects.reduced import ReducedModel
from vtable.runs.model import Run


class TableModel:
    """The linear uni-directional servo loop carrying the runs' specimen (report ch. 7)
    plus `effects`: `fit` the base loop and the effects' parameters on the training part
    of the runs, `score` the held-out error, `predict` a run's channels."""

    def __init__(self, effects: Sequence[str] = ()) -> None:
        self.effects = tuple(effects)
        self.physics_: Physics | None = None

    def fit(self, runs: Sequence[Run]) -> TableModel:
        """Fit on the runs' training segments (at the analysis rate, see
        `vtable.diagnose.compare.analysis_run`); `notes_` lists what the readers reported,
        the resampling done and the channels left out, `flags_` the fitted parameters at a
        bound."""
        d = Diagnoser(runs, self.effects, catalog=[])
        self._diagnoser = d
        self.physics_, self.train_error_ = d.fit(d.start)
        self.notes_ = list(d.notes)
        self.flags_ = d.at_bounds(self.physics_)
        self.base_ = d.base_table(self.physics_)
        return self

    def score(self, runs: Sequence[Run] | None = None) -> float:
        return self.comparison(runs).error

    def comparison(self, runs: Sequence[Run] | None = None, detail: bool = True) -> Comparison:
        d = self._diagnoser if runs is None else Diagnoser(runs, self.effects, catalog=[])
        return d.score(self.physics_, detail=detail)

    def predict(self, run: Run) -> dict[str, np.ndarray]:
        """The run's predictable channels (SI) at the run's own sample rate."""
        return ReducedModel(self.physics_).predict(run)
