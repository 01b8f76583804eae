"""The backward step (`engine.Diagnoser`): after an addition, the model is refitted
without each effect added before it, and the first one whose keeping is no longer a gain
the selection would count (`selection.failing`) is removed."""

from __future__ import annotations

from collections.abc import Callable

from vtable.diagnose.compare import compare
from vtable.diagnose.selection import failing
from vtable.diagnose.statistics import held_out_gain
from vtable.diagnose.verdict import State
from vtable.diagnose.workers import CandidateFit
from vtable.models.physics import Physics


def backward_step(diag, st: State, names: list[str], fitted: dict[str, CandidateFit],
                  progress: Callable[[int, int, str], None], done: int, steps: int, k: int
                  ) -> tuple[Physics, float, float] | None:
    """The current model of `diag` (a `Diagnoser`) against each fit in `fitted` without
    one of `names`; the first whose keeping is not a gain is removed (recorded in the last
    round). Returns (model, error, cost) after a removal, else None."""
    pred_cur = st.stages[-1].predictions
    for name in names:
        physics, pred = fitted[name].physics, fitted[name].predictions
        if isinstance(pred, Exception) or fitted[name].screened:  # screened: kept
            continue
        fails = failing(held_out_gain(pred, pred_cur, diag.runs, diag.campaign.noise),
                        st.current, name, diag.table_view)
        if not fails:
            continue
        err = compare(pred, diag.runs, scored="held", floor=diag.floor).error
        rnd = st.rounds[-1]
        rnd.removed[name] = (
            f"no longer needed once the later effects are in: without it (base "
            f"recalibrated) the held-out error is {err:.2%}; keeping it is not a gain "
            "the noise cannot produce: " + "; ".join(fails))
        rnd.error = err
        st.adopt(f"without_{name}", physics, err, pred)
        progress(done, steps, f"round {k}: removed {name}")
        return physics, err, fitted[name].cost
    return None
