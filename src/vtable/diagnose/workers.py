"""Candidate fits in worker processes: the diagnosis's candidates are independent, and a
fit's Python parts (least squares, building the model, residuals) hold the GIL, so threads
share one core for them; processes use every core.

`CandidatePool(n, files)` keeps `n` spawned workers for the life of the interpreter (one
pool per set of user effect files, made on first use): each loads those files, ignores
Ctrl-C (the parent sets the shared stop event instead, which every fit checks between
simulations) and keeps the last campaign it read (`CampaignFile`: pickled once by the
parent, so a task carries a path, not the runs). `fit(...)` returns a future of
(physics, train error, flags, cost, screened, predictions or the error that prevented
them, CPU seconds).
"""

from __future__ import annotations

import atexit
import contextlib
import importlib.machinery
import multiprocessing
import multiprocessing.util
import os
import pickle
import signal
import sys
import tempfile
import time
import uuid
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any

import numpy as np

from vtable.controllers import kinds
from vtable.diagnose.calibration import Calibration
from vtable.diagnose.campaign import Campaign
from vtable.diagnose.model import TableModel
from vtable.effects.registry import get as effect
from vtable.effects.registry import load_file
from vtable.errors import VtableError
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.params.specimen import NoSpecimen

_POOLS: dict[tuple[int, tuple[tuple[str, str], ...]], CandidatePool] = {}

# -- in the worker ----------------------------------------------------------------------
_STOP: Any = None
_CAMPAIGN: tuple[str, Campaign] | None = None


def _init(files: tuple[tuple[str, str], ...], stop) -> None:
    """A worker's start: Ctrl-C is the parent's to handle, the user's files are loaded
    (("effects", path) and ("controller", path) pairs), the kernels warmed up."""
    global _STOP
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _STOP = stop
    for what, f in files:
        (load_file if what == "effects" else kinds.load_file)(f)
    _warm_up()


def _warm_up() -> None:
    """Load the reduced model's compiled kernels (linear and nonlinear) from numba's cache
    while the parent fits its starting model."""
    t = np.arange(4) * 0.005
    for effects in ({}, {"actuator_friction": {}}):
        ReducedModel(Physics(nominal_open_loop(), NoSpecimen(), effects)).simulate(t, 0 * t)


def _ping() -> None:
    """A task that starts a worker."""


def _fit(path: str, start: Physics, name: str | None, baseline: float | None,
         seed: dict[str, float] | None, calibration: Calibration) -> tuple:
    """`TableModel(start=start, multistart=name, ...)` fitted on the campaign pickled at
    `path`, and its predictions (the module docstring's tuple)."""
    global _CAMPAIGN
    if _CAMPAIGN is None or _CAMPAIGN[0] != path:
        with open(path, "rb") as f:
            _CAMPAIGN = (path, pickle.load(f))
    return fitted(TableModel(start=start, multistart=name, stop=_STOP,
                             calibration=calibration, baseline=baseline, seed=seed),
                  _CAMPAIGN[1])


def fitted(model, campaign: Campaign) -> tuple:
    """Fit `model` (a `TableModel`) on `campaign`: (physics, train error, flags, cost,
    screened, its predictions or the error that prevented them, CPU seconds of this
    thread) — what a candidate's fit hands the diagnosis, in a worker or in its own
    process."""
    t0 = time.thread_time()
    m = model.fit(campaign)
    try:
        pred: Any = m.predictions(campaign)
    except VtableError as exc:  # the fit found no model it could build
        pred = exc
    flags = list(m.flags_)
    if not isinstance(pred, Exception):  # an effect fitted beyond what the runs reach
        flags += [why for name, v in m.physics_.effects.items()
                  if (why := effect(name).unseen(v, pred))]
    return (m.physics_, m.train_error_, flags, m.cost_, m.screened_, pred,
            time.thread_time() - t0)


# -- in the parent ----------------------------------------------------------------------
class CandidatePool:
    """`n` worker processes for candidate fits (see the module docstring)."""

    def __init__(self, n: int, files: tuple[tuple[str, str], ...]) -> None:
        ctx = multiprocessing.get_context("spawn")
        self.stop = ctx.Event()
        self.executor = ProcessPoolExecutor(max_workers=n, mp_context=ctx, initializer=_init,
                                            initargs=(files, self.stop))
        # start every worker now (each submit starts one), without the caller's main module:
        # a spawned process runs the main script again unless it is guarded by
        # `if __name__ == "__main__"`, and nothing the workers are sent needs it (vtable's
        # functions and objects; a user's effects come from their files)
        main = sys.modules["__main__"]
        spec = getattr(main, "__spec__", None)
        main.__spec__ = importlib.machinery.ModuleSpec("vtable.__main__", None)
        try:
            for _ in range(n):
                self.executor.submit(_ping)
        finally:
            main.__spec__ = spec

    @classmethod
    def get(cls, n: int, files: tuple[tuple[str, str], ...]) -> CandidatePool:
        key = (n, files)
        pool = _POOLS.get(key)
        if pool is None:
            if not _POOLS:
                # multiprocessing's own exit hook runs this before it waits for child
                # processes (in a process that is itself a worker, atexit never runs)
                multiprocessing.util.Finalize(None, shutdown, exitpriority=100)
            pool = _POOLS[key] = cls(n, files)
        return pool

    def fit(self, campaign: str, start: Physics, name: str | None, baseline: float | None,
            seed: dict[str, float] | None, calibration: Calibration) -> Future:
        """A candidate fit on the campaign pickled at `campaign` (`CampaignFile`)."""
        return self.executor.submit(_fit, campaign, start, name, baseline, seed, calibration)

    def shutdown(self) -> None:
        self.executor.shutdown(wait=True, cancel_futures=True)


class CampaignFile:
    """A campaign pickled once into a temporary file the workers read (each keeps the last
    one it read): a task carries its path, not the runs. `close()` removes it."""

    def __init__(self, campaign: Campaign) -> None:
        # a unique name: a worker recognises the campaign it holds by its path
        fd, self.path = tempfile.mkstemp(prefix=f"vtable-campaign-{uuid.uuid4().hex}-",
                                         suffix=".pickle")
        with os.fdopen(fd, "wb") as f:
            pickle.dump(campaign, f, protocol=pickle.HIGHEST_PROTOCOL)
        _FILES.add(self.path)

    def close(self) -> None:
        _FILES.discard(self.path)
        with contextlib.suppress(OSError):
            os.remove(self.path)


_FILES: set[str] = set()


def shutdown() -> None:
    """End every worker pool (a later diagnosis starts new workers)."""
    for pool in _POOLS.values():
        pool.stop.set()
        pool.shutdown()
    _POOLS.clear()


@atexit.register
def _close() -> None:
    for path in list(_FILES):
        with contextlib.suppress(OSError):
            os.remove(path)
    shutdown()
