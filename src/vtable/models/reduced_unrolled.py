"""The reduced model's RK4 with its mechanics unrolled for the model's shape.

`reduced_kernel._steps` steps any model: its coordinates q, q̇, the servo states and the
auxiliary loops' w in one array, the matrices read in loops whose lengths are known only
when it runs. Compiled that way, every state and matrix entry is read through a pointer
that may alias the arrays written, so nothing stays in a register: on the README
campaign's friction model (3 coordinates, 1 loop) it took 227–248 ns a step. This module
writes, for one stage set and one shape (n coordinates, m auxiliary loops), the same
arithmetic with q, q̇, w as local variables and the matrices' numbers in one array, each
read where it is used, the servo states left in their array and stepped by the stage set's
own `dof_drive`, `fed_back` and `actuator_rates` (a stage law keeps taking its states as
array slices): 170 ns a step with the numbers as a tuple, and a quarter less with the
array (a tuple is passed by value: its ~50 numbers were copied into each of the four calls
of `_rates` a step; a README friction model's 2,647-sample run, 5,294 steps, measured on
one host: 516 → 386 µs, 97 → 73 ns a step, and 481 µs with the numbers unpacked from the
array at the top of `_rates`). Another day on this project's machine, 5,294 steps of
that model (its nominal values, the El Centro run) took 900 µs, 170 ns a step, both at the
commit that measured 386 µs and at a later one: the host's speed for this loop varies
twofold, so compare only figures taken together. The histories are bit-identical (the
same operations in the same order; `tests/models/test_unrolled.py` compares them).

A model with force elements, or whose element needs numba's reference counting, is
stepped by `reduced_kernel._steps` (a law run as Python never reaches either:
`ReducedModel.histories`); so is a shape beyond `MAX_COORDINATES` coordinates or
`MAX_LOOPS` loops, and one whose kernel did not compile (`refuse`). The module of a shape
is written where the stage sets' are (`compose.generated_module`:
`vtable_stages_<key>_q<n>a<m>_<hash of its text>.py`) and compiled once (numba's cache).

The mechanics' law (M q̈ = bF F + fe − K q − C q̇ + Fw w − c₂|q̇|q̇, the loops' ẇ) is
written here as text and in `reduced_kernel._rates`: the tests hold the two to the same
bits.
"""

from __future__ import annotations

import hashlib
import inspect
import textwrap
from collections.abc import Callable

import numpy as np

from vtable._numba import first_compile
from vtable.hydraulics.compose import generated_module
from vtable.models.reduced_kernel import _blown

#: the most coordinates (and auxiliary loops) a shape is unrolled for
MAX_COORDINATES = 8
MAX_LOOPS = 4

_KERNELS: dict[tuple[str, int, int], Callable] = {}


def constants(model) -> np.ndarray:
    """The numbers `_steps` of the model's shape reads (see `_source`), in one array: the
    actuator's direction, its law's T⁺ and T (1 x 1), g, k_p, k_v, then bF, K, C, Fw, c₂,
    M⁻¹, Aw, Wq, Wv. Kept on the model by its arrays' identity (`simulate`): an array
    replaced is read anew, one changed in place would not be (nothing changes them in
    place)."""
    parts = [model.ax, [model.Tp[0, 0], model.T[0, 0], model.g[0], model.kp[0], model.kv[0]],
             model.bF, model.K.ravel(), model.C.ravel(), model.Fw.ravel(), model.c2,
             model.Minv.ravel(), model.Aw.ravel(), model.Wq.ravel(), model.Wv.ravel()]
    return np.concatenate([np.asarray(p, dtype=float).ravel() for p in parts])


def kernel(model) -> Callable | None:
    """The unrolled `_steps(xc, dt, c, sp, z, zt, kz, Q, Qd, Qdd, F, PL)` for `model`'s
    stage set and shape, or None when it is stepped by `reduced_kernel._steps` (see the
    module docstring)."""
    comp = model.element
    nq, na = model.M.shape[0], model.Aw.shape[0]
    if (model.elem is not None or not comp.key.endswith("u") or nq > MAX_COORDINATES
            or na > MAX_LOOPS or model.T.shape != (1, 1)):
        return None
    key = (comp.key, nq, na)
    if key not in _KERNELS:
        try:
            _KERNELS[key] = _module(comp, nq, na)._steps
        except (OSError, SyntaxError, ImportError):  # cannot be written or read: the
            _KERNELS[key] = None  # generic loop steps this shape
    return _KERNELS[key]


def refuse(model) -> None:
    """`model`'s stage set and shape are stepped by the generic loop from now on (its
    unrolled kernel did not compile: a law that allocates, which the generic loop then
    compiles with numba's reference counting)."""
    _KERNELS[(model.element.key, model.M.shape[0], model.Aw.shape[0])] = None


def _module(comp, nq: int, na: int):
    """The shape's module (`compose.generated_module`): its name carries a hash of its
    text, so a module another version of this generator wrote is never read back."""
    stage = comp.module
    text = _source(stage.__name__, nq, na)
    # numba checks a cached kernel against its own file only: the `_blown` it inlines is
    # in the name too
    digest = hashlib.sha256((text + inspect.getsource(_blown.py_func)).encode()
                            ).hexdigest()[:12]
    return generated_module(f"{stage.__name__}_q{nq}a{na}_{digest}", lambda: text)


def _source(stage_module: str, nq: int, na: int) -> str:
    """The module text for `nq` coordinates and `na` auxiliary loops, calling the stage
    module `stage_module`. Each line does what `reduced_kernel._rates`, `_stage`,
    `_advance` and `_record` do, in their order."""
    q = [f"q{i}" for i in range(nq)]
    v = [f"v{i}" for i in range(nq)]
    w = [f"w{a}" for a in range(na)]
    names = ([f"ax{i}" for i in range(nq)] + ["t", "T00", "g0", "kp0", "kv0"]
             + [f"bF{i}" for i in range(nq)]
             + [f"K{i}_{j}" for i in range(nq) for j in range(nq)]
             + [f"C{i}_{j}" for i in range(nq) for j in range(nq)]
             + [f"Fw{i}_{a}" for i in range(nq) for a in range(na)]
             + [f"c2{i}" for i in range(nq)]
             + [f"M{i}_{j}" for i in range(nq) for j in range(nq)]
             + [f"Aw{a}_{b}" for a in range(na) for b in range(na)]
             + [f"Wq{a}_{j}" for a in range(na) for j in range(nq)]
             + [f"Wv{a}_{j}" for a in range(na) for j in range(nq)])
    state = q + v + w
    c = {name: f"c[{k}]" for k, name in enumerate(names)}  # each number where it is used
    body = [*(f"    # c: {line}" for line in textwrap.wrap(" ".join(names), 80)),
            "    xa = 0.0", *[f"    xa += {c[f'ax{i}']} * q{i}" for i in range(nq)],
            "    va = 0.0", *[f"    va += {c[f'ax{i}']} * v{i}" for i in range(nq)],
            "    p_fb = fed_back(z, 0, sp)",
            f"    drive = {c['T00']} * dof_drive(xc, {c['t']} * xa, {c['t']} * p_fb, "
            f"{c['t']} * va, {c['g0']}, {c['kp0']}, {c['kv0']}, z, 0, sp, dz, True)",
            "    force = actuator_rates(z, 0, drive, va, sp, dz)"]
    for i in range(nq):
        body.append(f"    r{i} = {c[f'bF{i}']} * force + 0.0")
        body += [f"    r{i} -= {c[f'K{i}_{j}']} * q{j} + {c[f'C{i}_{j}']} * v{j}"
                 for j in range(nq)]
        body += [f"    r{i} += {c[f'Fw{i}_{a}']} * w{a}" for a in range(na)]
        body.append(f"    r{i} -= {c[f'c2{i}']} * abs(v{i}) * v{i}")
    for i in range(nq):
        body.append(f"    a{i} = 0.0")
        body += [f"    a{i} += {c[f'M{i}_{j}']} * r{j}" for j in range(nq)]
    for a in range(na):
        body.append(f"    d{a} = 0.0")
        body += [f"    d{a} += {c[f'Aw{a}_{b}']} * w{b}" for b in range(na)]
        body += [f"    d{a} += {c[f'Wq{a}_{j}']} * q{j} + {c[f'Wv{a}_{j}']} * v{j}"
                 for j in range(nq)]
    rates = v + [f"a{i}" for i in range(nq)] + [f"d{a}" for a in range(na)]
    body.append(f"    return ({', '.join([*rates, 'force'])},)")
    n = len(state)

    def trial(k: str, h: str) -> str:
        return ", ".join(f"{s} + {h} * {k}[{i}]" for i, s in enumerate(state))

    steps = [
        "    n = xc.shape[0]",
        "    ns = z.shape[0]",
        *[f"    {s} = 0.0" for s in state],
        "    for k in range(n):",
        "        x0 = xc[k]",
        "        x1 = xc[min(k + 1, n - 1)]",
        "        xm = 0.5 * (xc[k] + x1)",
        "        for i in range(ns):",
        "            zt[i] = z[i]",
        f"        d1 = _rates({', '.join(state)}, zt, x0, c, sp, kz[0])",
        f"        F[k] = d1[{n}]",
        "        PL[k] = z[0]",
        *[f"        Q[k, {i}] = q{i}" for i in range(nq)],
        *[f"        Qd[k, {i}] = v{i}" for i in range(nq)],
        *[f"        Qdd[k, {i}] = d1[{nq + i}]" for i in range(nq)],
        "        if k == n - 1:",
        "            return",
        "        h = 0.5 * dt",
        "        for i in range(ns):",
        "            zt[i] = z[i] + h * kz[0, i]",
        f"        d2 = _rates({trial('d1', 'h')}, zt, xm, c, sp, kz[1])",
        "        for i in range(ns):",
        "            zt[i] = z[i] + h * kz[1, i]",
        f"        d3 = _rates({trial('d2', 'h')}, zt, xm, c, sp, kz[2])",
        "        for i in range(ns):",
        "            zt[i] = z[i] + dt * kz[2, i]",
        f"        d4 = _rates({trial('d3', 'dt')}, zt, x1, c, sp, kz[3])",
        "        s = dt / 6.0",
        *[f"        {st} += s * (d1[{i}] + 2 * d2[{i}] + 2 * d3[{i}] + d4[{i}])"
          for i, st in enumerate(state)],
        "        for i in range(ns):",
        "            z[i] += s * (kz[0, i] + 2 * kz[1, i] + 2 * kz[2, i] + kz[3, i])",
        "        if not np.isfinite(q0) or abs(q0) > 10.0:",
        "            _blown(k + 1, Q, Qd, Qdd, F, PL)",
        "            return",
    ]
    return "\n".join([
        f'"""Generated by vtable.models.reduced_unrolled for {stage_module}: {nq} '
        f'coordinates, {na} auxiliary loops. Do not edit."""',
        "",
        "import numpy as np",
        "from numba import njit",
        "",
        f"from {stage_module} import actuator_rates, dof_drive, fed_back",
        "from vtable.models.reduced_kernel import _blown",
        "",
        "",
        "@njit(cache=True)",  # called four times a step, compiled once (inlined: 3 s)
        f"def _rates({', '.join(state)}, z, xc, c, sp, dz):",
        *body,
        "",
        "",
        "@njit(cache=True, nogil=True, _nrt=False)",
        "def _steps(xc, dt, c, sp, z, zt, kz, Q, Qd, Qdd, F, PL):",
        *steps,
        "",
    ])


def simulate(steps: Callable, model, xc: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
    """`steps` (the model's `kernel`) from rest over the upsampled command `xc` at step
    `dt`: q, q̇, q̈ (n_t x coordinates), the actuator force and its load pressure P_L, as
    `reduced_kernel.simulate_reduced` returns them."""
    arrays = model.integrated
    kept = model.__dict__.get("_unrolled_constants")  # by these arrays: a model whose K
    if kept is None or any(a is not b for a, b in zip(kept[0], arrays, strict=True)):  # is
        kept = model.__dict__["_unrolled_constants"] = (arrays, constants(model))  # replaced
    consts = kept[1]  # reads it anew
    n, nq, ns = xc.shape[0], model.M.shape[0], model.element.module.NS
    Q, Qd, Qdd = np.empty((n, nq)), np.empty((n, nq)), np.empty((n, nq))
    F, PL = np.empty(n), np.empty(n)
    with first_compile(steps):
        steps(xc, dt, consts, model.sp, np.zeros(ns), np.empty(ns), np.empty((4, ns)), Q, Qd,
              Qdd, F, PL)
    return Q, Qd, Qdd, F, PL
