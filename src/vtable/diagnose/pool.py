"""Where a diagnosis's fits run, and how Ctrl-C stops them.

`Fits` dispatches the candidate fits of a round (and the backward step's refits) as Dask
tasks (`vtable.diagnose.workers`: a local cluster of forked worker processes, one per core,
or a lab's scheduler, `scheduler`), to threads when a user's effect or controller kind was
registered from code rather than a file (another process could not load it), or runs them
one after the other in the calling thread with `workers=1`. It owns the stop flag every
fit checks between simulations. On Dask a core that would wait for a longer fit of its
batch takes the next fit in line (`dispatch`'s `ahead`), which the next batch then takes
over, and fits that need nothing the caller is still making start before it (`begin`):
every result the same, sooner.

`in_thread` runs the loop in a thread of its own while the caller's thread only waits and
reports progress: an interrupt there (Ctrl-C, or a progress callback raising) sets the stop
flags (this process's and the workers' Dask event), pending fits are cancelled, running
ones end at their next look at the flag, and the interrupt is raised again once the
loop's thread has ended.
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path
from typing import Any

from distributed import as_completed as dask_completed

from vtable.controllers import kinds
from vtable.diagnose.calibration import Calibration
from vtable.diagnose.campaign import Campaign
from vtable.diagnose.model import TableModel
from vtable.diagnose.residuals import StopRequestedError
from vtable.diagnose.workers import Tasks, cluster, estimator_job, fitted
from vtable.effects.registry import is_user, source_file

#: the processes the candidates are fitted in by default (two on this project's machines)
WORKERS = min(2, os.cpu_count() or 1)


class Fits:
    """The fits of one diagnosis: `dispatch` runs them where `workers` and `scheduler`
    say, `halt` stops them, `close` releases what the workers hold for it.

    `model(**job)` makes the estimator a fit runs in this process (`Diagnoser.model`,
    sharing `stop`).
    """

    def __init__(self, campaign: Campaign, catalog: Sequence[str], workers: int,
                 calibration: Calibration,
                 model: Callable[..., TableModel], scheduler: str | None = None) -> None:
        self.campaign, self.catalog, self.workers = campaign, list(catalog), workers
        self.calibration, self.model, self.scheduler = calibration, model, scheduler
        self.stop = threading.Event()
        self.tasks: Tasks | None = None  # this diagnosis's tasks on Dask, once started
        self.on_dask = False  # whether its fits ran as Dask tasks
        self._ahead: dict[Any, Any] = {}  # fits started ahead of their turn: key -> future

    def here(self, job: dict[str, Any]) -> tuple:
        """`workers.fitted` of `job` (the estimator's keywords) in this process: no frame
        made ahead (`frame_after`: this process makes it when it is needed)."""
        return fitted(self.model(**estimator_job(job)[0]), self.campaign)

    def user_files(self) -> tuple[tuple[str, str, str], ...] | None:
        """The user files the workers must load for this diagnosis, (kind, path, text),
        the controller's first; None when an effect or controller kind was registered from
        code (no file another process can load)."""
        files = []
        table = self.campaign.runs[0].table()  # TableDescription or None (the EERC table)
        kind = table.controller.kind if table is not None and table.controller else None
        if kind is not None and kind not in kinds.BUILT_IN:  # a lab's controller: its file
            f = kinds.source_file(kind)
            if f is None:
                return None
            files.append(("controller", f))
        for e in self.catalog:
            if is_user(e):
                f = source_file(e)
                if f is None:
                    return None
                files.append(("effects", f))
        return tuple((what, f, Path(f).read_text()) for what, f in dict.fromkeys(files))

    def start(self) -> Tasks | None:
        """This diagnosis's tasks on the Dask cluster (`workers.cluster`: made on first
        use), or None: one worker, or a user's effect registered from code."""
        if self.workers < 2 and not self.scheduler:
            return None
        files = self.user_files()
        if files is None:
            return None
        if self.tasks is None:
            self.tasks = Tasks(cluster(self.workers, self.scheduler), self.campaign, files)
            self.on_dask = True
        return self.tasks

    def warm(self, models: list) -> None:
        """Start the workers now and have them compile (or load) the kernels of `models`
        (`Physics`: the first round's candidates) while this process fits the starting
        model: a first run's compiling uses every core from the start (`Tasks.warm`).
        Nothing without Dask workers. Started here, with the runs read and the `Diagnoser`
        made, not sooner: forking the workers before the runs were read made the README
        campaign's diagnosis 8 % slower (+1.2 s of worker CPU outside the fits); starting
        them in a thread beside the starting fit (which would need numba's compiler lock
        held across the fork) was not measurably faster through the warm process."""
        tasks = self.start()
        if tasks is not None:
            tasks.warm(models)

    def dispatch(self, jobs: list[tuple[Any, tuple]], meanwhile: Callable[[], Any] | None = None,
                 ahead: Sequence[tuple[Any, tuple]] | Callable[[], Sequence] = ()
                 ) -> Iterator[tuple[Any, tuple]]:
        """Run fits (key, the estimator's keywords: start, multistart, ...) on every core and
        yield (key, `workers.fitted`'s tuple) as each finishes: as Dask tasks, or in
        threads when a user's effect cannot be loaded in another process; `meanwhile`, the
        caller's work that needs no fit, runs in this thread once they are submitted (first,
        when they run here). On a stop, pending fits are cancelled and running ones end at
        their next simulation.

        `ahead`: fits that may be asked for next, in order (or a function giving them, asked
        again after each result). On Dask, a core that one of `jobs` frees while fewer of
        them than cores still run takes the first of those not started at once; a later
        `dispatch` asking for it takes its result (the same fit, started sooner), and
        `drop_ahead` stops those never asked for. What is fitted, and so every result, is
        the same as without: only idle time is used (a round's refinements, run two by two,
        waited on the longer of each pair, and on the last screens)."""
        if not jobs:
            if meanwhile is not None:
                meanwhile()
            return
        if self.workers == 1 and not self.scheduler:  # one after the other, here
            if meanwhile is not None:
                meanwhile()
            for key, job in jobs:
                yield key, self.here(job)
            return
        tasks = self.start()
        if tasks is not None:
            futures = {(self._ahead.pop(key) if key in self._ahead else
                        tasks.submit(job, self.calibration)): key for key, job in jobs}
            if meanwhile is not None:
                meanwhile()
            asked, left = set(futures.values()), len(futures)
            for fut in dask_completed(list(futures)):
                left -= 1
                fit = fut.result()
                if fit is None:  # a worker's fit stopped (`workers._fit`)
                    raise StopRequestedError
                yield futures[fut], fit
                if 0 < left < max(1, self.workers):  # a core is free while others run
                    spare = [(k, j) for k, j in (ahead() if callable(ahead) else ahead)
                             if k not in self._ahead and k not in asked]
                    if spare:
                        self._ahead[spare[0][0]] = tasks.submit(spare[0][1], self.calibration)
            return
        with ThreadPoolExecutor(max_workers=self.workers) as threads:
            pending = {threads.submit(self.here, job): key for key, job in jobs}
            if meanwhile is not None:
                meanwhile()
            try:
                for fut in as_completed(pending):
                    yield pending[fut], fut.result()
            finally:
                for fut in pending:
                    fut.cancel()

    def begin(self, jobs: list[tuple[Any, dict]]) -> None:
        """Start `jobs` (key, the estimator's keywords) on Dask now, before the caller's
        other work: the `dispatch` that asks for them takes them over, as it does the fits
        started `ahead` (a round's backward refits run while its frame is taken). Nothing
        without Dask workers (`dispatch` runs them)."""
        tasks = self.start()
        if tasks is None:
            return
        for key, job in jobs:
            if key not in self._ahead:
                self._ahead[key] = tasks.submit(job, self.calibration)

    def drop_ahead(self, keys: Sequence[Any] | None = None) -> None:
        """Stop the fits started ahead of their turn (`ahead`, `begin`) that no `dispatch`
        asked for: those of `keys`, or all."""
        for key in list(self._ahead) if keys is None else keys:
            if key in self._ahead:
                self.tasks.drop(self._ahead.pop(key))

    def halt(self) -> None:
        """Stop the fits: this process's and the workers' (at their next look)."""
        self.stop.set()
        if self.tasks is not None:
            self.tasks.halt()

    def close(self) -> None:
        """Release what the workers hold for this diagnosis (its campaign, its results)."""
        self.drop_ahead()
        if self.tasks is not None:
            self.tasks.close()
            self.tasks = None


def in_thread(target: Callable[[Callable[[tuple], None]], None],
              progress: Callable[..., None], halt: Callable[[], None],
              name: str = "vtable-diagnose") -> None:
    """Run `target(post)` in a thread of its own; this thread hands each tuple it posts to
    `progress(*item)`, and returns as soon as it ends (it posts None last). Anything raised
    here (Ctrl-C, a failing progress callback) calls `halt()`, waits for the thread to end
    and is raised again; what `target` raises is its own to hand over (the diagnosis keeps
    it for the caller: `Diagnoser._loop`)."""
    events: queue.SimpleQueue = queue.SimpleQueue()

    def run() -> None:
        try:
            target(events.put)
        finally:
            events.put(None)

    worker = threading.Thread(target=run, daemon=True, name=name)
    worker.start()
    try:
        while True:
            try:
                item = events.get(timeout=0.1)  # a timeout: Ctrl-C is seen meanwhile
            except queue.Empty:
                continue
            if item is None:
                break
            progress(*item)
    except BaseException:
        halt()
        worker.join()
        raise
    worker.join()
