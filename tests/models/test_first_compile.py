"""Processes that meet the same uncompiled kernel at the same moment compile it once
(`vtable._numba.first_compile`): the others wait and load it from numba's cache."""

from __future__ import annotations

import importlib.util
import multiprocessing
import sys
import uuid

import numba
import pytest

from vtable import _numba

# a kernel that takes numba a while to compile, so that two processes' calls overlap
SOURCE = '''
import numpy as np
from numba import njit


@njit(cache=True)
def kernel(x):
    s = 0.0
    for i in range(x.shape[0]):
        v = x[i]
        s += np.tanh(v) * np.cos(v) + np.sqrt(abs(v)) - np.exp(-v * v) / (1.0 + v * v)
        if s > 1e9:
            s = np.log(s)
    return s
'''

needs_flock = pytest.mark.skipif(_numba.fcntl is None, reason="no flock on this system")


def _module(path):
    name = path.stem
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


def _call(path, barrier, out) -> None:
    try:
        import numpy as np

        kernel = _module(path).kernel
        barrier.wait(timeout=60)
        with _numba.first_compile(kernel):
            value = kernel(np.linspace(-1.0, 1.0, 101))
        out.put((kernel.stats.cache_misses.total(), kernel.stats.cache_hits.total(), value))
    except BaseException as e:  # said to the test, not left to hang it
        out.put(repr(e))


@pytest.fixture
def kernel_file(tmp_path, monkeypatch):
    """A new kernel's module in `tmp_path`, numba's cache (and the locks) there too."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "cache"))
    path = tmp_path / f"vtable_first_compile_{uuid.uuid4().hex[:12]}.py"
    path.write_text(SOURCE)
    return path


@needs_flock
def test_two_processes_compile_a_kernel_once(kernel_file):
    ctx = multiprocessing.get_context("fork")
    barrier, out = ctx.Barrier(2), ctx.Queue()
    procs = [ctx.Process(target=_call, args=(kernel_file, barrier, out), daemon=True)
             for _ in range(2)]
    try:
        for p in procs:
            p.start()
        results = [out.get(timeout=120) for _ in procs]
    finally:
        for p in procs:
            p.join(timeout=30)
            if p.is_alive():
                p.terminate()
    assert all(isinstance(r, tuple) for r in results), results
    # one compiled (a miss), the other waited and loaded what it cached (a hit)
    assert sorted((r[0], r[1]) for r in results) == [(0, 1), (1, 0)]
    assert results[0][2] == results[1][2]
    assert [p.exitcode for p in procs] == [0, 0]


@needs_flock
def test_a_kernel_numbas_cache_holds_is_loaded_without_the_lock(kernel_file):
    """A warm diagnosis's workers loaded their first kernels one after the other, the
    second waiting on the first's lock. A kernel in numba's cache takes no lock: here
    another process holds the lock (as if compiling) and the call still loads at once."""
    ctx = multiprocessing.get_context("fork")
    out = ctx.Queue()
    first = ctx.Process(target=_call, args=(kernel_file, ctx.Barrier(1), out), daemon=True)
    first.start()
    compiled = out.get(timeout=120)  # a process compiled it into the cache
    first.join(timeout=30)
    assert isinstance(compiled, tuple) and compiled[:2] == (1, 0), compiled
    lock = _numba._lock_path(_module(kernel_file).kernel)
    with open(lock, "a") as fh:
        _numba.fcntl.flock(fh, _numba.fcntl.LOCK_EX)  # held through the second's call
        second = ctx.Process(target=_call, args=(kernel_file, ctx.Barrier(1), out),
                             daemon=True)
        second.start()
        try:
            loaded = out.get(timeout=20)  # it would wait for the lock for ever
        finally:
            _numba.fcntl.flock(fh, _numba.fcntl.LOCK_UN)
            second.join(timeout=30)
            if second.is_alive():
                second.terminate()
    assert isinstance(loaded, tuple) and loaded[:2] == (0, 1), loaded
    assert loaded[2] == compiled[2]


@needs_flock
def test_the_lock_is_let_go_when_the_call_fails(kernel_file):
    kernel = _module(kernel_file).kernel
    with pytest.raises(numba.core.errors.TypingError), _numba.first_compile(kernel):
        kernel("not an array")
    lock = _numba._lock_path(kernel)
    with open(lock, "a") as fh:  # another file description: taken at once
        _numba.fcntl.flock(fh, _numba.fcntl.LOCK_EX | _numba.fcntl.LOCK_NB)
        _numba.fcntl.flock(fh, _numba.fcntl.LOCK_UN)


def test_a_plain_function_takes_no_lock(kernel_file):
    def plain(x):  # numba's JIT off: njit gives the function itself
        return 2 * x

    with _numba.first_compile(plain):
        assert plain(3) == 6
    assert not list((kernel_file.parent / "cache" / "locks").glob("*plain*.lock"))


def test_a_new_numba_release_gets_a_cache_folder_of_its_own(monkeypatch):
    """An older numba's index in the same folder would be stale, and a kernel whose index
    exists takes no lock: the folder's stamp holds numba's release."""
    stamp = _numba.sources_stamp()
    assert _numba._numba_release()  # read from numba's installed version file
    monkeypatch.setattr(_numba, "_numba_release", lambda: b'"version": "99.0.0"')
    assert _numba.sources_stamp() != stamp
