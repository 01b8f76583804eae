"""The simulator's stepping loop for linear controllers, compiled (numba).

While every controller is linear the whole control step is one matrix product
(`Simulator._fuse`), so the loop needs no Python: `step_linear` calls MuJoCo's
``mj_step1``/``mj_step2`` from its C library (the one the Python bindings loaded; the
functions are passed as ctypes pointers, so the compiled kernel is cached) and reads the
sensors and writes ``ctrl`` through the `MjData` arrays, which are views of MuJoCo's memory.
The per-step Python overhead of the bindings and of small numpy operations was half of the
step's time (issue 17).
"""

from __future__ import annotations

import ctypes
import functools
import glob
import os

import mujoco
import numpy as np

from vtable._numba import njit


@functools.cache
def mujoco_steps() -> tuple | None:
    """(mj_step1, mj_step2) of the MuJoCo C library as ctypes functions of the model's
    and data's addresses, or None where the library is not found (the Python loop runs)."""
    folder = os.path.dirname(mujoco.__file__)
    found = sorted(glob.glob(os.path.join(folder, "libmujoco.so*"))
                   + glob.glob(os.path.join(folder, "libmujoco*.dylib"))
                   + glob.glob(os.path.join(folder, "mujoco.dll")))
    if not found or not hasattr(mujoco.MjData, "_address"):
        return None
    try:
        lib = ctypes.CDLL(found[0])
        fns = (lib.mj_step1, lib.mj_step2)
    except (OSError, AttributeError):
        return None
    for f in fns:
        f.argtypes = [ctypes.c_uint64, ctypes.c_uint64]
        f.restype = None
    return fns


def sparse_rows(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`A`'s nonzeros by rows (compressed sparse rows: row starts, columns, values); the
    fused controller matrices are mostly zeros (the blocks of other actuators)."""
    rows, cols = np.nonzero(A)
    start = np.searchsorted(rows, np.arange(A.shape[0] + 1)).astype(np.int64)
    return start, cols.astype(np.int64), np.ascontiguousarray(A[rows, cols])


@njit(cache=True)
def step_linear(step1, step2, m: int, d: int, k0: int, k1: int,
                M2: tuple, N: tuple, offset: np.ndarray, cmd: np.ndarray,
                hist: np.ndarray, ns: int, n: int, dec: int, sens: np.ndarray,
                ctrl: np.ndarray, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray,
                rec_q: np.ndarray, rec_v: np.ndarray, rec_a: np.ndarray,
                rec_s: np.ndarray) -> None:
    """Steps k0..k1-1 of `Simulator.run`'s loop: the same history rows [s_k, z_k, u_k]
    (`hist`, flat: row k-1 through the s of row k is one product's input) and records.

    `M2` is the fused matrix (sparse rows), `N` the command matrices of c_{k-1}, c_k,
    c_{k+1} stacked (sparse rows over the 3·5 columns), `offset` the rest-length term."""
    W = hist.shape[1]
    nr = offset.shape[0]
    nc = cmd.shape[1]
    last = cmd.shape[0] - 1
    u0 = W - n
    flat = hist.reshape(-1)
    ms, mc, mv = M2
    cs, cc, cv = N
    for k in range(k0, k1):
        step1(m, d)
        r = (k + 1) * W
        for j in range(ns):
            flat[r + j] = sens[j]
        if k == 0:
            for j in range(ns):
                flat[j] = sens[j]
        b = k * W
        kp, kn = max(k - 1, 0), min(k + 1, last)
        for i in range(nr):
            acc = offset[i]
            for p in range(ms[i], ms[i + 1]):
                acc += mv[p] * flat[b + mc[p]]
            for p in range(cs[i], cs[i + 1]):
                j = cc[p]
                kk = kp if j < nc else (k if j < 2 * nc else kn)
                acc += cv[p] * cmd[kk, j % nc]
            flat[r + ns + i] = acc
        for j in range(n):
            ctrl[j] = flat[r + u0 + j]
        rec = k % dec == 0
        i = k // dec
        if rec:
            for j in range(qpos.shape[0]):
                rec_q[i, j] = qpos[j]
            for j in range(qvel.shape[0]):
                rec_v[i, j] = qvel[j]
        step2(m, d)
        if rec:
            for j in range(qvel.shape[0]):
                rec_v[i, j] += qvel[j]
                rec_a[i, j] = qacc[j]
            for j in range(sens.shape[0]):
                rec_s[i, j] = sens[j]
