"""Where a diagnosis's fits run, and how Ctrl-C stops them.

`Fits` dispatches the candidate fits of a round (and the backward step's refits) to the
`workers` processes (`vtable.diagnose.workers.CandidatePool`: every core, the campaign
pickled once), to threads when a user's effect was registered from code rather than a
file (another process could not load it), or runs them one after the other in the calling
thread with `workers=1`. It owns the stop flag every fit checks between simulations.

`in_thread` runs the loop in a thread of its own while the caller's thread only waits and
reports progress: an interrupt there (Ctrl-C, or a progress callback raising) sets the stop
flags (this process's and the workers' shared one), pending fits are cancelled, running
ones end at their next simulation, and the interrupt is raised again once the loop's
thread has ended.
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from typing import Any

from vtable.controllers import kinds
from vtable.diagnose.calibration import Calibration
from vtable.diagnose.campaign import Campaign
from vtable.diagnose.model import TableModel
from vtable.diagnose.workers import CampaignFile, CandidatePool, fitted
from vtable.effects.registry import is_user, source_file
from vtable.models.physics import Physics

#: the processes the candidates are fitted in by default (two on this project's machines)
WORKERS = min(2, os.cpu_count() or 1)


class Fits:
    """The fits of one diagnosis: `dispatch` runs them where `workers` says, `halt` stops
    them, `close` removes the campaign file the workers read.

    `model(start, multistart, baseline, seed)` makes the estimator a fit runs in this
    process (`Diagnoser.model`, sharing `stop`).
    """

    def __init__(self, campaign: Campaign, catalog: Sequence[str], workers: int,
                 calibration: Calibration,
                 model: Callable[[Physics, str | None, float | None, dict | None],
                                 TableModel]) -> None:
        self.campaign, self.catalog, self.workers = campaign, list(catalog), workers
        self.calibration, self.model = calibration, model
        self.stop = threading.Event()
        self.procs: CandidatePool | None = None  # the worker processes, once started
        self._file: CampaignFile | None = None  # the campaign pickled for them

    def here(self, start: Physics, name: str | None, baseline: float | None,
             seed: dict[str, float] | None) -> tuple:
        """`workers._fit` in this process."""
        return fitted(self.model(start, name, baseline, seed), self.campaign)

    def campaign_file(self) -> CampaignFile:
        if self._file is None:
            self.campaign.noise  # noqa: B018 (computed before pickling, with the table)
            self._file = CampaignFile(self.campaign)
        return self._file

    def pool(self) -> CandidatePool | None:
        """The worker processes for this diagnosis's candidates (`workers.CandidatePool`),
        or None: one worker, or an effect or controller kind registered from code (not from
        a file another process can load)."""
        if self.workers < 2:
            return None
        files = []
        for e in self.catalog:
            if is_user(e):
                f = source_file(e)
                if f is None:
                    return None
                files.append(("effects", f))
        table = self.campaign.runs[0].table()  # TableDescription or None (the EERC table)
        kind = table.controller.kind if table is not None and table.controller else None
        if kind is not None and kind not in kinds.BUILT_IN:  # a lab's controller: its file
            f = kinds.source_file(kind)
            if f is None:
                return None
            files.insert(0, ("controller", f))
        pool = CandidatePool.get(self.workers, tuple(sorted(set(files))))  # controller first
        if self.procs is None:  # this diagnosis's first round: a stop left from before goes
            pool.stop.clear()
        self.procs = pool
        return pool

    def dispatch(self, jobs: list[tuple[Any, tuple]]) -> Iterator[tuple[Any, tuple]]:
        """Run fits (key, (start, multistart effect, baseline, seed)) on every core and
        yield (key, `workers._fit`'s tuple) as each finishes: in the worker processes, or
        in threads when a user's effect cannot be loaded in another process. On a stop,
        pending fits are cancelled and running ones end at their next simulation."""
        if not jobs:
            return
        if self.workers == 1:  # one after the other, here
            for key, args in jobs:
                yield key, self.here(*args)
            return
        pool = self.pool()
        threads = None if pool is not None else ThreadPoolExecutor(max_workers=self.workers)
        futures: dict = {}
        try:
            for key, args in jobs:
                fut = (pool.fit(self.campaign_file().path, *args, self.calibration)
                       if pool is not None else threads.submit(self.here, *args))
                futures[fut] = key
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
        finally:
            if threads is not None:
                threads.shutdown(wait=True, cancel_futures=True)
            for fut in futures:
                fut.cancel()

    def halt(self) -> None:
        """Stop the fits: this process's and the worker processes' (at their next
        simulation)."""
        self.stop.set()
        if self.procs is not None:
            self.procs.stop.set()

    def close(self) -> None:
        """Remove the campaign file the workers read (a later round writes it again)."""
        if self._file is not None:
            self._file.close()
            self._file = None


def in_thread(target: Callable[[Callable[[tuple], None]], None],
              progress: Callable[..., None], halt: Callable[[], None],
              name: str = "vtable-diagnose") -> None:
    """Run `target(post)` in a thread of its own; this thread hands each tuple it posts to
    `progress(*item)`. Anything raised here (Ctrl-C, a failing progress callback) calls
    `halt()`, waits for the thread to end and is raised again."""
    events: queue.SimpleQueue = queue.SimpleQueue()
    worker = threading.Thread(target=target, args=(events.put,), daemon=True, name=name)
    worker.start()
    try:
        while worker.is_alive() or not events.empty():
            try:
                item = events.get(timeout=0.1)
            except queue.Empty:
                continue
            progress(*item)
    except BaseException:
        halt()
        worker.join()
        raise
    worker.join()
