"""Processes that meet the same uncompiled kernel at the same moment compile it once
(`compose.first_compile`): the others wait and load it from numba's cache."""

from __future__ import annotations

import importlib.util
import multiprocessing
import sys
import uuid

import pytest

from vtable.hydraulics import compose

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


def _module(path):
    name = path.stem
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


def _call(path, barrier, out) -> None:
    import numpy as np

    kernel = _module(path).kernel
    barrier.wait()
    with compose.first_compile(kernel):
        value = kernel(np.linspace(-1.0, 1.0, 101))
    out.put((kernel.stats.cache_misses.total(), kernel.stats.cache_hits.total(), value))


@pytest.mark.skipif(compose.fcntl is None, reason="no flock on this system")
def test_two_processes_compile_a_kernel_once(tmp_path):
    path = tmp_path / f"vtable_first_compile_{uuid.uuid4().hex[:12]}.py"
    path.write_text(SOURCE)
    ctx = multiprocessing.get_context("fork")
    barrier, out = ctx.Barrier(2), ctx.Queue()
    procs = [ctx.Process(target=_call, args=(path, barrier, out)) for _ in range(2)]
    for p in procs:
        p.start()
    results = [out.get(timeout=120) for _ in procs]
    for p in procs:
        p.join(timeout=60)
    misses = sorted(r[0] for r in results)
    hits = sorted(r[1] for r in results)
    assert misses == [0, 1]  # one compiled, the other loaded what it cached
    assert hits == [0, 1]
    assert results[0][2] == results[1][2]
