"""Candidate fits as tasks on Dask: the diagnosis's candidates are independent, and a fit's
Python parts (least squares, building the model, residuals) hold the GIL, so threads share
one core for them; Dask's worker processes use every core, on this machine or a lab's
cluster.

`cluster(n, scheduler)` is the Dask client the fits are submitted to: the scheduler at
`scheduler` (a lab's cluster: `vtable diagnose --scheduler tcp://host:8786`), or a local
cluster of `n` single-threaded worker processes, made once per process and kept. Locally
the workers are forked from this process (`distributed.worker.multiprocessing-method`
"fork"): they start in a tenth of a second with vtable imported and its compiled kernels
loaded, where spawned ones would import everything again; they ignore Ctrl-C (the
disposition they are forked with), which the parent handles. Right before the fork every
object this process holds is moved out of the garbage collector's sight (`gc.freeze`,
until `shutdown`): a collection in a worker or here no longer walks (and, in a worker,
copies page by page) the heap of the imports and the campaign (README campaign: 6 % less
CPU, 8 % less wall).

A diagnosis scatters its campaign to every worker once (`Tasks.campaign`) and submits
`_fit` tasks: each returns what `fitted` does (a `CandidateFit`). User files (effects
and controller kinds registered with `--effects-from`, `--controller-from`) are sent to
the workers as text and loaded there (`_load_files`), so a remote worker needs vtable
installed, not the user's files. A stop (Ctrl-C) sets a Dask `Event` and cancels every
fit; a running fit reads its cancellation from its worker's task state between
simulations, and the event every `POLL_S` (`StopFlag`); a fit stopped so returns None (a
task that raised would have its traceback pickled and sent, every module's path resolved
the first time: ~16,000 file-system calls in each worker).
"""

from __future__ import annotations

import atexit
import contextlib
import functools
import gc
import hashlib
import logging
import os
import signal
import tempfile
import threading
import time
import uuid
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, NamedTuple

import dask
import distributed.utils
import numpy as np
from distributed import Client, Event, LocalCluster, get_worker

from vtable.controllers import kinds
from vtable.diagnose.calibration import Calibration
from vtable.diagnose.campaign import Campaign
from vtable.diagnose.model import TableModel
from vtable.diagnose.residuals import StopRequestedError
from vtable.effects import registry as effects_registry
from vtable.effects.registry import get as effect
from vtable.errors import VtableError
from vtable.models.reduced import ReducedModel

#: seconds between two looks at a diagnosis's stop event from a running fit
POLL_S = 0.2


#: the states of a task its worker is running and still wants (`distributed`'s worker
#: state machine); a cancelled one is "cancelled", a forgotten one gone. "resumed" (a
#: cancelled task asked for again under its key) is not among them: a fit's key is never
#: asked for again (`pure=False`), so a resumed fit is one no dispatch waits for.
_RUNNING = ("executing", "long-running")


class StopFlag:
    """A diagnosis's stop, read by its fits as a `threading.Event` (`is_set`).

    In a worker the running task's own state is read at every look, which is no message:
    a task the client cancelled (`Tasks.drop`, `Tasks.halt`) stops at its next
    simulation (a fit started ahead and dropped as its round ended, read from the event
    alone, held a core of the next round for ~0.1 s). The diagnosis's Dask `Event`, which
    `Tasks.halt` sets as well, is looked at no more often than every `POLL_S` seconds (each
    look is a message to the scheduler): a fit submitted after a stop, which no cancel
    reached, ends at its first look."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._event: Any = None
        self._next = 0.0
        self._set = False
        self._worker: Any = None  # the worker this flag is read in (False: none)

    def _cancelled(self) -> bool:
        """Whether the task this thread runs is no longer wanted by its worker (cancelled
        or forgotten); False outside a Dask worker's task thread. The task is looked up at
        each call (a dictionary read), not kept."""
        if self._worker is None:
            try:
                self._worker = get_worker()
            except ValueError:
                self._worker = False
        if self._worker is False:
            return False
        try:
            key = self._worker.get_current_task()
        except (KeyError, AttributeError):  # not in one of the worker's task threads
            return False
        ts = self._worker.state.tasks.get(key)
        return ts is None or ts.state not in _RUNNING

    def is_set(self) -> bool:
        if self._set or self._cancelled():
            return True
        now = time.monotonic()
        if now >= self._next:
            self._next = now + POLL_S
            if self._event is None:
                self._event = Event(self.name)
            self._set = self._event.is_set()
        return self._set

    def __getstate__(self) -> dict:
        return {"name": self.name}

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["name"])


# -- in the worker ----------------------------------------------------------------------
_LOADED: set[str] = set()


def _load_files(files: tuple[tuple[str, str, str], ...]) -> None:
    """Load a diagnosis's user files in this worker, once each: (kind, path, text), kind
    "effects" or "controller"; from `path` where this machine holds it with that text (the
    module keeps the name it has in the parent), else from a copy of the text."""
    for what, path, text in files:
        digest = hashlib.sha256(text.encode()).hexdigest()[:16]
        if digest in _LOADED:
            continue
        p = Path(path)
        try:
            same = p.read_text() == text
        except OSError:
            same = False
        if not same:
            folder = Path(tempfile.gettempdir()) / f"vtable-user-{digest}"
            folder.mkdir(exist_ok=True)
            p = folder / p.name
            if not p.exists():
                p.write_text(text)
        registry = effects_registry if what == "effects" else kinds
        if not registry.loaded(p):  # a forked worker holds what the parent had loaded
            registry.load_file(p)
        _LOADED.add(digest)


def _fit(campaign: Campaign, job: dict[str, Any], calibration: Calibration, stop: StopFlag,
         files: tuple[tuple[str, str, str], ...]) -> tuple | None:
    """`TableModel(**job)` fitted on `campaign` (the module docstring's tuple), None when
    asked to stop; `job` holds the estimator's keywords (start, multistart, baseline, seed,
    frame, ...)."""
    _load_files(files)
    job, after = estimator_job(job)
    try:
        return fitted(TableModel(**{"calibration": calibration, **job}, stop=stop), campaign,
                      frame_after=after)
    except StopRequestedError:  # asked to stop (the module docstring)
        return None


def _warm(campaign: Campaign, physics: Any, files: tuple[tuple[str, str, str], ...]) -> bool:
    """Compile (or load from numba's cache) the kernels of `physics`'s reduced model in this
    worker: a few samples of the campaign's first run simulated. Whether it could be built
    (a model that cannot is the diagnosis's to report, not this task's)."""
    _load_files(files)
    r = campaign.runs[0]
    try:
        load_kernels(ReducedModel(physics.in_state(campaign.state(r)), campaign.table),
                     r.time, r.channel("h_span"))
    except VtableError:
        return False
    return True


#: the samples a model is stepped over to load its kernels (`load_kernels`)
WARM_SAMPLES = 4


def load_kernels(model: ReducedModel, t: np.ndarray, x: np.ndarray) -> None:
    """Compile (or load from numba's cache) `model`'s kernels in this process: its first
    `WARM_SAMPLES` samples of the command `x` at times `t` simulated (a diagnosis's
    workers before their fits, `_warm`; the warm process for its next commands,
    `vtable.warm.server`)."""
    model.simulate(t[:WARM_SAMPLES], x[:WARM_SAMPLES])


class CandidateFit(NamedTuple):
    """What a candidate's fit hands the diagnosis (`fitted`), from a worker or its own
    process."""

    physics: Any  # the fitted `Physics`
    train_error: float
    flags: list[str]
    cost: float  # the training cost (data and priors)
    screened: bool  # stopped by the screen (not refined)
    predictions: Any  # each run's channels, or the error that prevented them
    cpu_s: float  # CPU seconds of the thread that fitted it
    passed: Any  # where a screen that passed stopped (fitted scale), or None
    #: the next round's `projected.Frame` of the fitted model, should it be added (asked
    #: with `frame_after`, made for a refined fit only), or None
    frame: Any = None


def estimator_job(job: dict[str, Any]) -> tuple[dict[str, Any], bool]:
    """A fit's job as the estimator's keywords, and whether it asks for the next round's
    frame (`frame_after`, which `fitted` reads)."""
    return {k: v for k, v in job.items() if k != "frame_after"}, bool(job.get("frame_after"))


def fitted(model, campaign: Campaign, frame_after: bool = False) -> CandidateFit:
    """Fit `model` (a `TableModel`) on `campaign` (`CandidateFit`: what the diagnosis
    reads). `frame_after`: a refined fit (not screened, no screen stopped) also brings the
    frame the next round screens on were it added (`TableModel.frame_of`, as the diagnosis
    makes it): made here, beside the round's other fits, where the diagnosis would make it
    after the round with the cores idle."""
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
    cpu_s = time.thread_time() - t0  # the fit's own (what orders the next round's fits)
    frame = None
    if frame_after and not m.screened_ and m.passed_ is None and np.isfinite(m.cost_) and \
            not isinstance(pred, Exception):
        frame = TableModel.unfitted(campaign, m.calibration, m.stop).frame_of(m.physics_,
                                                                              campaign)
    return CandidateFit(m.physics_, m.train_error_, flags, m.cost_, m.screened_, pred,
                        cpu_s, m.passed_, frame)


# -- in the parent ----------------------------------------------------------------------
_CLIENTS: dict[tuple[int, str | None], Any] = {}
_LOCK = threading.Lock()


def cluster(n: int, scheduler: str | None = None):
    """The Dask client candidate fits run on (module docstring): the scheduler at
    `scheduler`, or this process's local cluster of `n` forked workers (made on first
    use); the local workers ignore Ctrl-C (`_fork_safe`)."""
    key = (n, scheduler)
    with _LOCK:
        client = _CLIENTS.get(key)
        if client is not None and client.status == "running":
            return client

        if scheduler:
            try:
                client = Client(scheduler, timeout=10)
            except OSError as e:
                raise VtableError(f"--scheduler {scheduler}: no Dask scheduler answers there "
                                  f"({e})") from None
        else:
            _fork_safe()
            _silence_distributed()
            _FORKING.set()  # the children forked now are our workers: Ctrl-C is ours
            gc.freeze()  # what exists now is the workers' too: no collection touches it
            try:
                with dask.config.set({"distributed.worker.multiprocessing-method": "fork",
                                      "distributed.worker.daemon": True,
                                      "distributed.scheduler.work-stealing": False,
                                      # a worker holds only the fit it runs: the next goes
                                      # to the first core free, in the order submitted (at
                                      # the default 1.1 a screen could queue behind a
                                      # round's long fit while the other core idled). Dask
                                      # queues so only "root-ish" tasks: many of one group
                                      # on few inputs. The fits' inputs are the campaign and
                                      # each round's frame (kept till the diagnosis ends):
                                      # past the default 5 of them, a later round's fits
                                      # would no longer count
                                      "distributed.scheduler.worker-saturation": 1.0,
                                      "distributed.scheduler.rootish-taskgroup-dependencies":
                                          1 << 20,
                                      # no statistical profiler sampling the fits' stacks
                                      # every 10 ms, fewer ticks and system samples: each
                                      # takes the interpreter lock from a fit
                                      "distributed.worker.profile.enabled": False,
                                      "distributed.admin.tick.interval": "500ms",
                                      # each worker's and nanny's look at its process's
                                      # memory (the limit kept), once a second, not ten
                                      # times: the nannies' ran in this process
                                      "distributed.worker.memory.monitor-interval": "1s",
                                      "distributed.admin.system-monitor.interval": "2s"}):
                    lc = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                      dashboard_address=":0", silence_logs=logging.CRITICAL)
                    client = Client(lc)
            except BaseException:
                if not any(k[1] is None for k in _CLIENTS):  # no local cluster holds it
                    gc.unfreeze()
                raise
            finally:
                _FORKING.clear()
        client.loop.asyncio_loop.set_exception_handler(_loop_error)
        _CLIENTS[key] = client
        return client


def _loop_error(loop, context: dict[str, Any]) -> None:
    """What Dask's event loop (in this process: the client's, and a local cluster's
    scheduler) could not hand to anyone, logged at distributed's debug level, not printed
    by asyncio's default handler: a scatter that Ctrl-C cut short failed in the scheduler
    as the workers left, and its task's exception, never retrieved, printed a traceback
    under the interruption's one line (once, in a clean-clone CI run), whenever it was
    collected, `shutdown`'s end included. What the client is asked for still raises
    where it is asked."""
    logging.getLogger("distributed").debug(context.get("message", "event loop error"),
                                           exc_info=context.get("exception"))


#: set while this process forks its local workers (`cluster`)
_FORKING = threading.Event()

#: distributed's own log level before a local cluster silenced it (`_silence_distributed`)
_LEVEL: list[int] = []


def _silence_distributed() -> None:
    """distributed's loggers silenced from a local cluster's start until `shutdown` has
    closed it, its closing included: `silence_logs` gives the handlers their levels back
    as the cluster's close ends, and a scatter that Ctrl-C had cut short then failed in the
    scheduler as the workers left, its traceback printed (once, under a full suite's
    load). distributed's level is given back by `shutdown`."""
    logger = logging.getLogger("distributed")
    if not _LEVEL:
        _LEVEL.append(logger.level)
    logger.setLevel(logging.CRITICAL)


@functools.cache
def _fork_safe() -> None:
    """What a worker forked from this process must not inherit as it is, set right after
    the fork in the child: distributed's executor for (de)serialising large messages
    (once its thread has run here, the child's copy has a thread that does not exist, and
    a large campaign would wait for it forever: each child gets a new one); and, for our
    workers (`_FORKING`), Ctrl-C, which the terminal sends to the whole process group and
    this process handles (a worker would print its traceback). This process's own
    handling of Ctrl-C is never changed, so an interrupt is never lost while they start."""
    def fresh() -> None:
        distributed.utils._offload_executor = ThreadPoolExecutor(
            max_workers=1, thread_name_prefix="Dask-Offload")
        if _FORKING.is_set():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        _HELD.clear()  # logging gives the child fresh handler locks

    os.register_at_fork(before=hold_logs, after_in_parent=let_logs_go, after_in_child=fresh)


#: the log handlers whose locks this process holds while it forks (`hold_logs`)
_HELD: list = []


def hold_logs() -> None:
    """Take every log handler's lock before this process forks, so that no other thread is
    writing a record at that moment: a stream's own lock, held then, would be held for ever
    in the child, and a worker's first log line would wait for it (a test run hung so:
    a forked worker in `StreamHandler.flush`, the scheduler's thread logging as the nanny
    forked). logging renews the handlers' locks in the child; `let_logs_go` releases them
    here."""
    loggers = [logging.getLogger(), *(v for v in list(logging.Logger.manager.loggerDict.values())
                                      if isinstance(v, logging.Logger))]
    handlers = list(dict.fromkeys(h for lg in loggers for h in lg.handlers))
    for h in handlers:
        h.acquire()
        _HELD.append(h)


def let_logs_go() -> None:
    """Release what `hold_logs` took (in the forking process, after the fork)."""
    while _HELD:
        _HELD.pop().release()


def running():
    """The client of the local cluster this process made, while it is up, or None (a
    diagnosis's report draws its figures there: `vtable.viz.diagnosis_report`)."""
    with _LOCK:
        for (_, scheduler), client in _CLIENTS.items():
            if scheduler is None and client.status == "running":
                return client
    return None


def shutdown() -> None:
    """End every cluster this process made (a later diagnosis starts new workers); the
    objects frozen for the local workers' fork (`cluster`) are collected again (a freeze
    of the program's own, without a local cluster of ours, is left alone), and
    distributed's log level is given back once they are closed (`_silence_distributed`)."""
    with _LOCK:
        local = any(scheduler is None for _, scheduler in _CLIENTS)
        for client in _CLIENTS.values():
            with contextlib.suppress(Exception):
                lc = client.cluster
                client.close()
                if lc is not None:
                    lc.close()
        _CLIENTS.clear()
        if local:
            gc.unfreeze()
        if _LEVEL:
            logging.getLogger("distributed").setLevel(_LEVEL.pop())


atexit.register(shutdown)


class Tasks:
    """One diagnosis's fits on a Dask client: the campaign scattered once, its stop event,
    its user files (`submit`, `halt`, `close`)."""

    def __init__(self, client, campaign: Campaign,
                 files: tuple[tuple[str, str, str], ...]) -> None:
        self.client, self.files = client, files
        self.stop = StopFlag(f"vtable-stop-{uuid.uuid4().hex}")
        self._campaign = client.scatter(campaign, broadcast=True, hash=False)
        self._futures: list = []
        self._frame: tuple[Any, Any] | None = None  # the round's frame and its future

    def submit(self, job: dict[str, Any], calibration: Calibration):
        """A fit (`_fit`) of `job` (stopped by this diagnosis's flag, or by cancelling its
        future); its frame, new to this round, scattered once."""
        frame = job.get("frame")
        if frame is not None:
            if self._frame is None or self._frame[0] is not frame:
                self._frame = (frame, self.client.scatter(frame, broadcast=True, hash=False))
                self._futures.append(self._frame[1])
            job = {**job, "frame": self._frame[1]}
        fut = self.client.submit(_fit, self._campaign, job, calibration, self.stop,
                                 self.files, pure=False)
        self._futures.append(fut)
        return fut

    def drop(self, fut) -> None:
        """Cancel a fit submitted ahead of its turn (`pool.Fits.dispatch`'s `ahead`,
        `pool.Fits.begin`): running, it stops at its next simulation (`StopFlag`)."""
        with contextlib.suppress(Exception):
            self.client.cancel([fut])

    def warm(self, models: list) -> None:
        """Have the workers compile (or load) the kernels of `models` (`Physics`), one task
        each, in this order, before the fits submitted after them."""
        self._futures += [self.client.submit(_warm, self._campaign, ph, self.files,
                                             pure=False) for ph in models]

    def halt(self) -> None:
        """Stop every fit: those not done cancelled (a running one stops at its next
        simulation), and the diagnosis's event set (a fit submitted after this ends at its
        first look at it: `StopFlag`)."""
        with contextlib.suppress(Exception):
            Event(self.stop.name, client=self.client).set()
        with contextlib.suppress(Exception):
            self.client.cancel([f for f in self._futures if not f.done()])

    def close(self) -> None:
        """Release the scattered campaign and the results the workers hold."""
        with contextlib.suppress(Exception):
            self.client.cancel([*self._futures, self._campaign])
        self._futures = []
