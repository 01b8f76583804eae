"""The reduced model's integrator (numba): generalized coordinates q with mass, stiffness
and damping matrices, one equivalent horizontal actuator stepped by the hydraulic element
(`vtable.hydraulics.element`: `dof_drive` and `actuator_rates`, the law the actuator
groups' `servo_rates` applies too), auxiliary linear states w (other control loops:
ẇ = Aw w + Wq q + Wv q̇, generalized force Fw w), quadratic dampers c₂|q̇|q̇, and force
elements with states z (`elem(q, q̇, z, p, f, ż)` adds generalized forces to f).

`simulate_reduced` integrates a model: the stage set's generated module's `_steps`,
calling the `elements` it defines (the force laws written into it, none in a module
without them; the coordinates given at run time: `vtable.hydraulics.compose`). It is
cached on disk with that module, so every process loads it compiled; it is compiled
without numba's reference counting, the step's functions inlined into it: an array handed
to a function in the loop cost two atomic counts each time, most of the step's time
(2.7 ms a call → 1.0 ms on the README campaign's training runs).
`simulate_reduced_python` runs the element code as Python for a law numba cannot compile.

A linear model (no force element, no quadratic damper, a linear hydraulic loop) is the
state-space system ẏ = A y + B x_c whose A and B are the same rates evaluated on unit
states (`linear_system`); `simulate_linear` steps it exactly for a command linear between
samples (first-order hold: the exponential of the augmented matrix over one step), the
same input the RK4 integrator assumes, at a fraction of its cost.
"""

from __future__ import annotations

import types
from collections.abc import Callable

import numpy as np

from vtable._numba import first_compile, njit
from vtable.controllers.force_law import named
from vtable.hydraulics.element import NS, actuator_rates, dof_drive, fed_back


def work_size(nq: int) -> int:
    """Length of `_rates`'s scratch array."""
    return nq


@njit(cache=True, inline="always")
def _rates(y, xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw, fe, dy,
           ws):
    """Rates of the main state y = [q, q̇, servo (NS), w] with extra generalized forces fe;
    returns the actuator force. The equivalent actuator is one lumped actuator on one DOF
    (T, Tp 1 x 1): its drive is `dof_drive`, its rates `actuator_rates`. `ws`: scratch of
    `work_size(nq)` (no allocation, no array views: this runs four times per step)."""
    na = Aw.shape[0]
    s0 = 2 * nq
    xa = 0.0
    va = 0.0
    for i in range(nq):
        xa += ax[i] * y[i]
        va += ax[i] * y[nq + i]
    t = Tp[0, 0]
    p_fb = fed_back(y, s0, sp)
    drive = T[0, 0] * dof_drive(xc, t * xa, t * p_fb, t * va, g[0], kp[0], kv[0], y, s0, sp,
                                dy, True)
    force = actuator_rates(y, s0, drive, va, sp, dy)
    for i in range(nq):
        r = bF[i] * force + fe[i]
        for j in range(nq):
            r -= K[i, j] * y[j] + C[i, j] * y[nq + j]
        for j in range(na):
            r += Fw[i, j] * y[s0 + NS + j]
        r -= c2[i] * abs(y[nq + i]) * y[nq + i]
        ws[i] = r
    for i in range(nq):
        dy[i] = y[nq + i]
        acc = 0.0
        for j in range(nq):
            acc += Minv[i, j] * ws[j]
        dy[nq + i] = acc
    for a in range(na):
        r = 0.0
        for b in range(na):
            r += Aw[a, b] * y[s0 + NS + b]
        for j in range(nq):
            r += Wq[a, j] * y[j] + Wv[a, j] * y[nq + j]
        dy[s0 + NS + a] = r
    return force


@njit(cache=True, inline="always")
def _record(k, y, k1, nq, Q, Qd, Qdd, PL):
    """Sample k of the histories: q, q̇, q̈ (from the rates k1) and P_L."""
    PL[k] = y[2 * nq]
    for i in range(nq):
        Q[k, i] = y[i]
        Qd[k, i] = y[nq + i]
        Qdd[k, i] = k1[nq + i]


@njit(cache=True, inline="always")
def _trial(yt, y, kx, c):
    """RK4's trial state yt = y + c kx."""
    for i in range(y.shape[0]):
        yt[i] = y[i] + c * kx[i]


@njit(cache=True, inline="always")
def _advance(y, k1, k2, k3, k4, dt, k, Q, Qd, Qdd, F, PL):
    """RK4's step y += dt/6 (k1 + 2 k2 + 2 k3 + k4); a state that blows up ends the
    histories with NaN from sample k + 1 on (returns False)."""
    for i in range(y.shape[0]):
        y[i] += dt / 6.0 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i])
    if not np.isfinite(y[0]) or abs(y[0]) > 10.0:
        _blown(k + 1, Q, Qd, Qdd, F, PL)
        return False
    return True


@njit(cache=True, inline="always")
def _blown(k, Q, Qd, Qdd, F, PL):
    """NaN in the histories from sample k on (a state that blew up); loops, not slices:
    they compile in a fraction of the time."""
    for i in range(k, F.shape[0]):
        F[i] = np.nan
        PL[i] = np.nan
        for j in range(Q.shape[1]):
            Q[i, j] = np.nan
            Qd[i, j] = np.nan
            Qdd[i, j] = np.nan


@njit(cache=True, inline="always")
def _stage(yt, y, kk, s, dt, x0, xm, x1):
    """RK4 stage s's trial state into yt (a copy of y, then y + dt/2 k1, y + dt/2 k2,
    y + dt k3) and returns its command (x at the step's start, middle, middle, end). The
    rates are evaluated on yt at every stage: a law writes its states' rates into dz, never
    its states z."""
    if s == 0:
        for i in range(y.shape[0]):
            yt[i] = y[i]
        return x0
    if s == 3:
        _trial(yt, y, kk[2], dt)
        return x1
    _trial(yt, y, kk[s - 1], 0.5 * dt)
    return xm


def _element_rates(y, xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
                   elem, ne, pe, dy):
    """Rates of y = [main state, element states]: the elements' forces, then `_rates`."""
    m = y.shape[0] - ne
    fe = np.zeros(nq)
    dze = np.zeros(ne)
    elem(y[:nq], y[nq:2 * nq], y[m:], pe, fe, dze)
    force = _rates(y[:m], xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
                   fe, dy[:m], np.zeros(nq))  # work_size(nq)
    for k in range(ne):
        dy[m + k] = dze[k]
    return force


def _element_integrate(xc, dt, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv,
                       Fw, elem, ne, pe):
    """`_steps_elements` as plain Python (see `_element_rates`), for a force law numba
    cannot compile (`simulate_reduced_python`)."""
    n = xc.shape[0]
    ny = 2 * nq + NS + Aw.shape[0] + ne
    y = np.zeros(ny)
    Q, Qd, Qdd, F = np.empty((n, nq)), np.empty((n, nq)), np.empty((n, nq)), np.empty(n)
    PL = np.empty(n)
    k1, k2, k3, k4 = np.empty(ny), np.empty(ny), np.empty(ny), np.empty(ny)
    for k in range(n):
        F[k] = _element_rates(y, xc[k], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw,
                              Wq, Wv, Fw, elem, ne, pe, k1)
        Q[k], Qd[k], Qdd[k], PL[k] = y[:nq], y[nq:2 * nq], k1[nq:2 * nq], y[2 * nq]
        if k == n - 1:
            break
        xm = 0.5 * (xc[k] + xc[k + 1])
        _element_rates(y + 0.5 * dt * k1, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv,
                       Aw, Wq, Wv, Fw, elem, ne, pe, k2)
        _element_rates(y + 0.5 * dt * k2, xm, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv,
                       Aw, Wq, Wv, Fw, elem, ne, pe, k3)
        _element_rates(y + dt * k3, xc[k + 1], nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp,
                       kv, Aw, Wq, Wv, Fw, elem, ne, pe, k4)
        y += dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        if not np.isfinite(y[0]) or abs(y[0]) > 10.0:
            Q[k + 1:], Qd[k + 1:], Qdd[k + 1:], F[k + 1:] = np.nan, np.nan, np.nan, np.nan
            PL[k + 1:] = np.nan
            break
    return Q, Qd, Qdd, F, PL


@njit(cache=True)
def elements(q, qd, z, p, f, dz, ia, ib):
    """The force elements' generalized forces (a stand-in: the generated module of a stage
    set with force-element laws defines its own, `vtable.hydraulics.compose`)."""
    return


@njit(cache=True, inline="always")
def _rates_with_elements(y, xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq,
                         Wv, Fw, pe, ia, ib, ne, dy, fe, ws):
    """Rates of y = [main state, element states]: the elements' forces into fe (their state
    rates into dy's tail), then `_rates`; no allocation."""
    m = y.shape[0] - ne
    for i in range(nq):
        fe[i] = 0.0
    elements(y[:nq], y[nq:2 * nq], y[m:], pe, fe, dy[m:], ia, ib)
    return _rates(y[:m], xc, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
                  fe, dy[:m], ws)


@njit(cache=True, nogil=True, _nrt=False)
def _steps(xc, dt, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw, pe, ia,
           ib, ne, y, yt, kk, fe, ws, Q, Qd, Qdd, F, PL):
    """RK4 at step dt (the command linear between samples) into the histories q, q̇, q̈
    (Q, Qd, Qdd: n_t x nq), the actuator force F and its load pressure P_L (n_t), from the
    state y at zero (scratch yt, the stages' rates kk (4 x ny), fe, ws: `simulate_reduced`
    makes them); the force elements (`elements` of the stage set's module, none in a
    module without force laws) on coordinates ia, ib given at run time, their ne states at
    the end of y. A state that blows up ends the histories with NaN. The four RK4 stages
    are one loop, so the rates are compiled (inlined) once. No allocation."""
    n = xc.shape[0]
    for k in range(n):
        xm = 0.5 * (xc[k] + xc[min(k + 1, n - 1)])
        for s in range(4):
            xs = _stage(yt, y, kk, s, dt, xc[k], xm, xc[min(k + 1, n - 1)])
            f = _rates_with_elements(yt, xs, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv,
                                     Aw, Wq, Wv, Fw, pe, ia, ib, ne, kk[s], fe, ws)
            if s == 0:
                F[k] = f
                _record(k, y, kk[0], nq, Q, Qd, Qdd, PL)
                if k == n - 1:
                    return
        if not _advance(y, kk[0], kk[1], kk[2], kk[3], dt, k, Q, Qd, Qdd, F, PL):
            return


#: no force element: their parameters, and their coordinates (`simulate_reduced`)
NO_ELEMENTS = (np.zeros(0), np.zeros(0, dtype=np.int64))
#: the kernels a stage set's compiled element carries (`vtable.hydraulics.compose`; its
#: force laws, if any, written into its `elements`)
KERNELS = (_rates, _record, _trial, _stage, _blown, _advance, _rates_with_elements, _steps)


def simulate_reduced(module, xc, dt, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq,
                     Wv, Fw, pe=NO_ELEMENTS[0], ia=NO_ELEMENTS[1], ib=NO_ELEMENTS[1], ne=0):
    """RK4 at step dt of a stage set's compiled element (`module`: its `_steps`, with the
    force elements `pe`, `ia`, `ib`, `ne` when there are); returns q, q̇, q̈ (n_t x nq),
    the actuator force (n_t) and its load pressure P_L (n_t). The arrays are made here,
    so the compiled loop is the one function compiled per stage set."""
    n = xc.shape[0]
    ny = 2 * nq + module.NS + Aw.shape[0] + ne
    Q, Qd, Qdd = np.empty((n, nq)), np.empty((n, nq)), np.empty((n, nq))
    F, PL = np.empty(n), np.empty(n)
    with first_compile(module._steps):
        module._steps(xc, dt, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw,
                      pe, ia, ib, ne, np.zeros(ny), np.empty(ny), np.empty((4, ny)),
                      np.zeros(nq), np.zeros(nq), Q, Qd, Qdd, F, PL)
    return Q, Qd, Qdd, F, PL


def law_where(law: Callable) -> str:
    """A law's name and the file it lives in, for a message."""
    law = getattr(law, "py_func", law)
    code = getattr(law, "__code__", None)
    where = f" ({code.co_filename})" if code is not None else ""
    return f"{getattr(law, '__qualname__', law)}{where}"


def python_elements(elements: list, ix: dict[str, int]):
    """The force elements (`reduced.ForceElement`) as one Python function for
    `simulate_reduced_python` (a law numba cannot compile): every element's law on its
    relative motion, its force added to its coordinate and subtracted from the other.
    Returns (function, states, parameters)."""
    params = np.concatenate([e.params for e in elements]) if elements else np.zeros(0)
    spans = []
    s = o = 0
    for e in elements:
        spans.append((e, ix[e.a], None if e.b is None else ix[e.b], s, o))
        s, o = s + e.states, o + len(e.params)

    def combined(q, qd, z, p, f, dz):
        for e, i, j, s0, o0 in spans:
            d = q[i] - (q[j] if j is not None else 0.0)
            v = qd[i] - (qd[j] if j is not None else 0.0)
            vals = p[o0:o0 + len(e.params)]
            arg = named(e.names)(*vals) if e.names is not None else vals
            r = e.law(d, v, z[s0:s0 + e.states], arg, dz[s0:s0 + e.states])
            f[i] += r
            if j is not None:
                f[j] -= r

    return combined, s, params


def simulate_reduced_python(module, *args):
    """`_element_integrate` as plain Python, calling `module`'s compiled `_rates` (a stage
    set's)."""
    glb = dict(_element_integrate.__globals__)
    glb["_rates"], glb["NS"] = module._rates, module.NS
    glb["_element_rates"] = types.FunctionType(_element_rates.__code__, glb)
    return types.FunctionType(_element_integrate.__code__, glb)(*args)


def linear_system(module, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw):
    """(A, B, f_y, f_u) of a linear model: ẏ = A y + B x_c and the actuator force
    f_y·y + f_u x_c, from `module._rates` (a stage set's element) on unit states (exact:
    the rates are linear)."""
    _rates = module._rates
    ny = 2 * nq + module.NS + Aw.shape[0]
    fe = np.zeros(nq)
    A, fy = np.empty((ny, ny)), np.empty(ny)
    dy, y = np.empty(ny), np.zeros(ny)
    ws = np.zeros(work_size(nq))
    with first_compile(_rates):
        for j in range(ny):
            y[:] = 0.0
            y[j] = 1.0
            fy[j] = _rates(y, 0.0, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv,
                           Fw, fe, dy, ws)
            A[:, j] = dy
        y[:] = 0.0
        fu = _rates(y, 1.0, nq, Minv, K, C, c2, bF, ax, sp, T, Tp, g, kp, kv, Aw, Wq, Wv, Fw, fe,
                    dy, ws)
    return A, dy.copy(), fy, fu


@njit(cache=True, nogil=True)
def simulate_linear(xc, nq, A, B, fy, fu, Phi, G0, G1):
    """The linear model stepped exactly (see the module docstring); the same outputs as
    `simulate_reduced`, NaN from where a state blows up."""
    n = xc.shape[0]
    ny = A.shape[0]
    y = np.zeros(ny)
    yn = np.empty(ny)
    Q, Qd, Qdd, F = np.empty((n, nq)), np.empty((n, nq)), np.empty((n, nq)), np.empty(n)
    PL = np.empty(n)
    for k in range(n):
        u = xc[k]
        f = fu * u
        for j in range(ny):
            f += fy[j] * y[j]
        F[k] = f
        PL[k] = y[2 * nq]
        for i in range(nq):
            Q[k, i] = y[i]
            Qd[k, i] = y[nq + i]
            a = B[nq + i] * u
            for j in range(ny):
                a += A[nq + i, j] * y[j]
            Qdd[k, i] = a
        if k == n - 1:
            break
        du = xc[k + 1] - u
        for i in range(ny):
            s = G0[i] * u + G1[i] * du
            for j in range(ny):
                s += Phi[i, j] * y[j]
            yn[i] = s
        for i in range(ny):
            y[i] = yn[i]
        if not np.isfinite(y[0]) or abs(y[0]) > 10.0:
            _blown(k + 1, Q, Qd, Qdd, F, PL)
            break
    return Q, Qd, Qdd, F, PL


@njit(cache=True, nogil=True)
def simulate_modal(xc, phi, g0, g1, C, D, every):
    """A stable linear model's outputs stepped in its modal coordinates z (A = V Λ V⁻¹,
    z = V⁻¹ y): z_{k+1} = e^{λh} z_k + γ₀ x_k + γ₁ (x_{k+1} - x_k), the first-order hold
    of `simulate_linear` mode by mode (`g0`, `g1`: γ₀, γ₁ with V⁻¹B folded in); the
    outputs Re(C z) + D x at every `every`-th step (C: the output rows times V, each
    conjugate pair once, doubled). Returns (outputs, samples)."""
    n = xc.shape[0]
    m = phi.shape[0]
    no = C.shape[0]
    n_out = (n - 1) // every + 1
    Y = np.empty((no, n_out))
    z = np.zeros(m, dtype=np.complex128)
    j = 0
    for k in range(n):
        u = xc[k]
        if k % every == 0:
            for o in range(no):
                s = D[o] * u
                for i in range(m):
                    s += (C[o, i] * z[i]).real
                Y[o, j] = s
            j += 1
        if k == n - 1:
            break
        du = xc[k + 1] - u
        for i in range(m):
            z[i] = phi[i] * z[i] + g0[i] * u + g1[i] * du
    return Y
