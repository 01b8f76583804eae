"""Fits of the report's models to transfer functions (§6.7, §7.6, App. D, §3.3).

Every fit returns a `Fit`: parameters, their standard errors (from the Jacobian at the
optimum, σ²(JᵀJ)⁻¹ with σ² the residual variance), goodness of fit (R² of the fitted
quantity and the normalised RMS residual) and its `flags` (vtable.ident.validity: at a
bound, standard error larger than the value, poor R² or coherence, a damping the
frequency resolution does not resolve, too few averages). A fit knows the resolution of
its lines and their coherence; `Fit.checked(averages=...)` adds what only the caller
knows.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import scipy.optimize

from vtable.analytic.closed_forms import transmissibility
from vtable.analytic.sdof import coefficients_7_9
from vtable.errors import VtableError
from vtable.ident.validity import Flag, fit_flags

TWO_PI = 2 * np.pi


@dataclass(frozen=True)
class Fit:
    """Fitted parameters with standard errors, goodness of fit and validity flags.

    `bounds` are the optimiser's bounds per parameter, `modes` the (frequency, damping)
    parameter pairs, `context` what the data allowed (resolution_hz, averages, and
    coherence: the mean γ² of the fitted lines), `correlation` the parameters' pairwise
    correlations ("a,b" -> ρ); `flags` follow from all of them
    (`vtable.ident.validity.fit_flags`)."""

    params: dict[str, float]
    stderr: dict[str, float]
    r2: float
    nrmse: float
    n_points: int
    method: str
    extra: dict[str, float] = field(default_factory=dict)
    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)
    modes: tuple[tuple[str, str], ...] = ()
    context: dict[str, float] = field(default_factory=dict)
    flags: tuple[Flag, ...] = ()
    correlation: dict[str, float] = field(default_factory=dict)

    def __getitem__(self, key: str) -> float:
        return self.params[key]

    def checked(self, **context: float | None) -> Fit:
        """This fit with `context` added (None values ignored) and its flags recomputed."""
        ctx = {**self.context, **{k: float(v) for k, v in context.items() if v is not None}}
        new = replace(self, context=ctx)
        return replace(new, flags=fit_flags(new))

    def flags_of(self, param: str) -> list[Flag]:
        return [f for f in self.flags if f.param == param]

    @property
    def ok(self) -> bool:
        """No flags: every number of the fit can be quoted as a result."""
        return not self.flags

    def to_json(self) -> dict[str, Any]:
        return {"params": self.params, "stderr": self.stderr, "r2": self.r2,
                "nrmse": self.nrmse, "method": self.method, "n_points": self.n_points,
                "resolution_hz": self.context.get("resolution_hz"),
                "averages": self.context.get("averages"),
                "flags": [f.to_json() for f in self.flags]}


def _spacing(f: np.ndarray) -> float | None:
    """The line spacing of a frequency axis (the resolution of a Welch estimate)."""
    d = np.diff(np.asarray(f, dtype=float))
    return float(np.median(d)) if len(d) else None




def _stats(resid: np.ndarray, target: np.ndarray, J: np.ndarray | None, names: Sequence[str],
           x: np.ndarray, corr: dict[str, float] | None = None
           ) -> tuple[dict[str, float], float, float]:
    """Standard errors, R², normalised RMS residual; pairwise parameter correlations go
    into `corr` ("a,b" -> ρ) when given."""
    n, p = len(resid), len(names)
    ss = float(resid @ resid)
    tot = float(np.sum((target - target.mean()) ** 2)) or 1.0
    stderr = {k: float("nan") for k in names}
    if J is not None and n > p:
        try:
            cov = np.linalg.inv(J.T @ J) * ss / (n - p)
            stderr = {k: float(np.sqrt(max(cov[i, i], 0.0))) for i, k in enumerate(names)}
            d = np.sqrt(np.abs(np.diag(cov)))
            if corr is not None and np.all(d > 0):
                r = cov / np.outer(d, d)
                corr.update({f"{names[i]},{names[j]}": float(r[i, j])
                             for i in range(p) for j in range(i + 1, p)})
        except np.linalg.LinAlgError:
            pass
    rms_t = float(np.sqrt(np.mean(target**2))) or 1.0
    return stderr, 1 - ss / tot, float(np.sqrt(ss / n)) / rms_t


def _select(f, H, coherence, band, min_coherence):
    """The lines of (f, H) in `band` with coherence >= `min_coherence`, √coherence
    weights, and the fit context (resolution of the whole axis, mean γ² of the lines)."""
    f, H = np.asarray(f, dtype=float), np.asarray(H, dtype=complex)
    df = _spacing(f)
    ok = np.isfinite(H) & (f > 0)
    if band is not None:
        ok &= (f >= band[0]) & (f <= band[1])
    w = np.ones_like(f)
    if coherence is not None:
        coherence = np.asarray(coherence, dtype=float)
        ok &= coherence >= min_coherence
        w = np.sqrt(np.clip(coherence, 0, 1))
    if ok.sum() < 4:
        where = "" if band is None else f" in {band[0]:.3g}-{band[1]:.3g} Hz"
        raise VtableError(f"only {int(ok.sum())} usable frequency lines{where} with coherence "
                          f">= {min_coherence:g} (a fit needs 4)")
    ctx = {"resolution_hz": df,
           "coherence": None if coherence is None else float(np.mean(w[ok] ** 2))}
    return f[ok], H[ok], w[ok], ctx


def _least_squares(fun: Callable, x0, lb, ub, names, target, method: str,
                   modes: tuple[tuple[str, str], ...] = (), context=None, **kw) -> Fit:
    sol = scipy.optimize.least_squares(fun, x0, bounds=(lb, ub), x_scale="jac", **kw)
    corr: dict[str, float] = {}
    stderr, r2, nrmse = _stats(sol.fun, target, sol.jac, names, sol.x, corr)
    fit = Fit(dict(zip(names, map(float, sol.x), strict=True)), stderr, r2, nrmse,
              len(sol.fun), method, {"cost": float(sol.cost), "nfev": float(sol.nfev)},
              {k: (float(a), float(b)) for k, a, b in zip(names, lb, ub, strict=True)}, modes,
              correlation=corr)
    return fit.checked(**(context or {}))


# ---- the bare-table servo loop (eq 6.15) -----------------------------------------------
def h_open_loop(f_hz, f_o: float, xi_o: float, k_o: float) -> np.ndarray:
    """H = k_o/(s(s²/ω_o² + 2ξ_o s/ω_o + 1) + k_o), eq 6.15b (`h_resonator_lag` with
    neither lag nor resonator)."""
    return h_resonator_lag(f_hz, f_o, xi_o, k_o, 0.0, 1.0, 0.0, 0.0)


def h_open_loop_lag(f_hz, f_o: float, xi_o: float, k_o: float, tau: float) -> np.ndarray:
    """Eq 6.15b with a first-order servovalve lag inside the loop: the flow follows the
    valve command through 1/(1 + τs), so the open loop of eq 6.13 becomes
    G = k_o/(s(1 + τs)(s²/ω_o² + 2ξ_o s/ω_o + 1)) and H = G/(1 + G)
    = k_o/(s(1 + τs)(s²/ω_o² + 2ξ_o s/ω_o + 1) + k_o). τ = 0 is eq 6.15b; the DC gain
    is 1 (a valve-integrator loop is type 1)."""
    return h_resonator_lag(f_hz, f_o, xi_o, k_o, tau, 1.0, 0.0, 0.0)


def h_resonator_lag(f_hz, f_o: float, xi_o: float, k_o: float, tau: float, f_s: float,
                    xi_s: float, u: float) -> np.ndarray:
    """Eq 7.9 with the valve lag of `h_open_loop_lag`: the loop of eq 6.15 carrying a
    resonator of mass ratio u = m_s/m_t (ω_s, ξ_s) on the platen. The platen's inertia
    and the oil column's damping see the dynamic mass 1 + u T_s, T_s the resonator's
    transmissibility (eq 7.8, `closed_forms.transmissibility`), so
    H = k_o/(s(1 + τs)[(1 + u T_s)(s²/ω_o² + 2ξ_o s/ω_o) + 1] + k_o);
    τ = 0 is eq 7.9 exactly (its coefficients a0-a5, with the a2 typo corrected), u = 0
    is `h_open_loop_lag`."""
    s = 1j * TWO_PI * np.asarray(f_hz, dtype=float)
    w = TWO_PI * f_o
    # no resonator (u = 0): no transmissibility either (an undamped one at f_s is
    # infinite on that line, and 0 x inf is not 0)
    dynamic = 1 + u * transmissibility(f_hz, f_s, xi_s) if u else 1.0
    d = dynamic * (s * s / w**2 + 2 * xi_o * s / w) + 1
    return k_o / (s * (1 + tau * s) * d + k_o)


def h_type0(f_hz, gain: float, f_n: float, zeta: float) -> np.ndarray:
    """A type-0 second-order loop (no integrator: an electrodynamic shaker, a stiff
    plant under proportional control): H = K ω_n²/(s² + 2ζω_n s + ω_n²), DC gain K."""
    s = 1j * TWO_PI * np.asarray(f_hz, dtype=float)
    w = TWO_PI * f_n
    return gain * w**2 / (s * s + 2 * zeta * w * s + w**2)


def phase_crossover(f: np.ndarray, H: np.ndarray) -> float:
    """The first frequency where the phase of H passes -180° (§6.7: H(iω_o) is real and
    negative, eq 6.19), by linear interpolation of the unwrapped phase."""
    ph = np.unwrap(np.angle(H))
    below = np.nonzero(ph <= -np.pi)[0]
    if len(below) == 0 or below[0] == 0:
        raise VtableError("the phase never reaches -180°: cannot start f_o (§6.7)")
    i = below[0]
    return float(np.interp(-np.pi, [ph[i], ph[i - 1]], [f[i], f[i - 1]]))


def fit_open_loop(f, H, coherence=None, band=None, min_coherence=0.9) -> Fit:
    """(f_o, ξ_o, k_o) of eq 6.15 by bounded nonlinear least squares on the amplitude
    (weighted by √coherence), f_o started at the 180° phase crossing (§6.7)."""
    f, H, w, ctx = _select(f, H, coherence, band, min_coherence)
    f0 = phase_crossover(f, H)
    h0 = float(np.abs(np.interp(f0, f, np.abs(H))))
    xi0 = 0.5
    k0 = 2 * xi0 * TWO_PI * f0 * h0 / (1 + h0)  # from eq 6.19 with H(iω_o) = -h0
    mag = np.abs(H)

    def resid(x):
        return w * (np.abs(h_open_loop(f, *x)) - mag)

    return _least_squares(resid, [f0, xi0, max(k0, 1.0)], [0.1, 0.01, 0.1],
                          [200.0, 5.0, 1e4], ("f_o", "xi_o", "k_o"), w * mag,
                          "eq 6.15 amplitude fit", (("f_o", "xi_o"),), ctx,
                          xtol=1e-10, ftol=1e-10)


# ---- table + SDOF (eq 7.9) ----------------------------------------------------------------
def h_table_sdof(f_hz, f_o, xi_o, k_o, f_s, xi_s, u, tau: float = 0.0) -> np.ndarray:
    """x_t/x_c of eq 7.9 (a2 with ξ_o, the derived form).

    Eq 7.9 is k_o N(s)/P(s) with N = s² + 2ξ_sω_s s + ω_s²: the loop's open-loop gain is
    k_o N/(P - k_o N). A first-order servovalve lag τ in the loop (as in
    `h_open_loop_lag`) divides it by (1 + τs): H = k_o N/((1 + τs)(P - k_o N) + k_o N);
    τ = 0 is eq 7.9."""
    s = 1j * TWO_PI * np.asarray(f_hz, dtype=float)
    b, a = coefficients_7_9(TWO_PI * f_o, xi_o, k_o, TWO_PI * f_s, xi_s, u)
    num, den = np.polyval(b, s), np.polyval(a, s)
    if tau:
        den = (1 + tau * s) * (den - num) + num
    return num / den


def fit_table_sdof(f, H, u: float, coherence=None, band=None, min_coherence=0.9,
                   tau: float = 0.0) -> Fit:
    """(f_o, ξ_o, k_o, f_s, ξ_s) of eq 7.9 with the mass ratio u known, on the amplitude
    (§7.6); f_o started just below the 180° crossing, f_s at the notch. A known valve
    lag `tau` (s) is held in the loop (`h_table_sdof`), not fitted."""
    f, H, w, ctx = _select(f, H, coherence, band, min_coherence)
    mag = np.abs(H)
    f0 = phase_crossover(f, H)
    low = f < 0.6 * f0
    fs0 = float(f[low][np.argmin(mag[low])]) if low.any() else f0 / 3

    def resid(x):
        return w * (np.abs(h_table_sdof(f, *x, u, tau)) - mag)

    return _least_squares(resid, [0.95 * f0, 0.5, 25.0, fs0, 0.03],
                          [0.1, 0.01, 0.1, 0.05, 1e-4], [200.0, 5.0, 1e4, 100.0, 0.5],
                          ("f_o", "xi_o", "k_o", "f_s", "xi_s"), w * mag,
                          "eq 7.9 amplitude fit", (("f_o", "xi_o"), ("f_s", "xi_s")), ctx,
                          xtol=1e-10, ftol=1e-10)


# ---- a single mode, complex curve fit --------------------------------------------------
def h_mode(f_hz, f_n, xi_n, gain, power: int = 2) -> np.ndarray:
    """gain·Ω^power/(ω_n² - Ω² + 2jξ_nω_nΩ): eq 3.11 for power = 2 (x_s/x_eff), a
    receptance for power = 0."""
    W = TWO_PI * np.asarray(f_hz, dtype=float)
    wn = TWO_PI * f_n
    return gain * W**power / (wn**2 - W**2 + 2j * xi_n * wn * W)


def fit_mode(f, H, band, coherence=None, power: int = 2, min_coherence: float = 0.0) -> Fit:
    """f_n, ξ_n and a real gain of one mode by nonlinear least squares on the complex
    H (real and imaginary parts, weighted by √coherence) in `band`; started from the
    amplitude peak and the half-power width."""
    f, H, w, ctx = _select(f, H, coherence, band, min_coherence)
    W = TWO_PI * f
    mag = np.abs(H) / W**power
    i = int(np.argmax(mag))
    fn0, g0 = float(f[i]), 1.0
    try:
        xi0 = min(max(half_power(f, mag).params["xi_n"], 0.002), 0.3)
    except VtableError:
        xi0 = 0.02
    g0 = float(mag[i] * 2 * xi0 * (TWO_PI * fn0) ** 2)
    if np.real(H[i] / h_mode(f[i], fn0, xi0, 1.0, power)) < 0:
        g0 = -g0
    scale = float(np.max(np.abs(H)))

    def resid(x):
        r = (h_mode(f, *x, power) - H) * w / scale
        return np.concatenate([r.real, r.imag])

    target = np.concatenate([(H * w / scale).real, (H * w / scale).imag])
    return _least_squares(resid, [fn0, xi0, g0], [0.5 * fn0, 1e-4, -np.inf],
                          [2 * fn0, 0.9, np.inf], ("f_n", "xi_n", "gain"), target,
                          "complex single-mode fit", (("f_n", "xi_n"),), ctx,
                          xtol=1e-12, ftol=1e-12)


# ---- appendix D amplitude fitting ---------------------------------------------------------
def amplitude_fit(f, A, weighting: str = "A3", band=None, coherence=None) -> Fit:
    """Appendix D: ω_n, ξ_n, P_n of a single mode from amplitudes A_k (force/acceleration
    to displacement form, eq D.2) by linear least squares: eq D.4 (A³ weighting, the
    report's choice) or eq D.3 (A²), normal equations D.10, parameters D.11. Amplitudes
    are normalised to max 1 (D.11b) and P rescaled. `coherence` (of the lines of f) only
    enters the validity flags."""
    f, A = np.asarray(f, dtype=float), np.abs(np.asarray(A))
    df = _spacing(f)
    ok = np.isfinite(A) & (f > 0)
    if band is not None:
        ok &= (f >= band[0]) & (f <= band[1])
    coh = None if coherence is None else float(np.mean(np.clip(coherence, 0, 1)[ok]))
    f, A = f[ok], A[ok]
    if len(f) < 4:
        where = "" if band is None else f" in {band[0]:.3g}-{band[1]:.3g} Hz"
        raise VtableError(f"appendix D fit needs at least 4 amplitudes; {len(f)} lines{where} "
                          f"at {df:.3g} Hz resolution" if df else
                          "appendix D fit needs at least 4 amplitudes")
    scale = A.max()
    a = A / scale
    W = TWO_PI * f
    if weighting == "A3":  # D.5: A³x1 + A³Ω²x2 - A x3 = -A³Ω⁴
        M = np.column_stack([a**3, a**3 * W**2, -a])
        rhs = -(a**3) * W**4
    elif weighting == "A2":  # D.3: A²D² - P² = 0
        M = np.column_stack([a**2, a**2 * W**2, -np.ones_like(a)])
        rhs = -(a**2) * W**4
    else:
        raise VtableError(f"weighting must be 'A3' (eq D.4) or 'A2' (eq D.3), got {weighting!r}")
    x, *_ = np.linalg.lstsq(M, rhs, rcond=None)  # = the normal equations D.10
    return _d11(x, f, a, scale, M, rhs, f"appendix D ({weighting})").checked(
        resolution_hz=df, coherence=coh)


def _d11(x, f, a, scale, M, rhs, method) -> Fit:
    x1, x2, x3 = x[:3]
    if x1 <= 0 or x3 <= 0:
        raise VtableError("appendix D fit failed: no single-mode peak in these amplitudes")
    wn = x1**0.25  # D.11
    xi2 = x2 / (4 * wn**2) + 0.5
    xi = float(np.sqrt(xi2)) if xi2 > 0 else float("nan")
    P = float(np.sqrt(x3)) * scale
    W = TWO_PI * f
    model = (P / scale) / np.sqrt((wn**2 - W**2) ** 2 + (2 * wn * xi * W) ** 2)
    resid = model - a
    stderr, r2, nrmse = _stats(resid, a, None, ("f_n", "xi_n", "P_n"), x)
    # parameter errors by linear propagation of the LSQ covariance of x
    n, p = M.shape
    sr = M @ x - rhs
    cov = np.linalg.pinv(M.T @ M) * float(sr @ sr) / max(n - p, 1)
    # ω_n = x1^¼, ξ² = x2/(4√x1) + ½: ∂ξ/∂x1 = -x2/(16 ξ x1^1.5), ∂ξ/∂x2 = 1/(8 ξ ω_n²)
    J = np.array([[0.25 * x1**-0.75 / TWO_PI, 0, 0],
                  [-x2 / (16 * xi * x1**1.5), 1 / (8 * xi * wn**2), 0],
                  [0, 0, scale / (2 * np.sqrt(x3))]])
    c = J @ cov[:3, :3] @ J.T
    stderr = {k: float(np.sqrt(max(c[i, i], 0))) for i, k in enumerate(("f_n", "xi_n", "P_n"))}
    return Fit({"f_n": wn / TWO_PI, "xi_n": xi, "P_n": P}, stderr, r2, nrmse, len(f), method,
               modes=(("f_n", "xi_n"),))


def amplitude_fit_global(f, amplitudes: Sequence, weighting: str = "A3", band=None) -> Fit:
    """Appendix D.2: one frequency and damping from several channels (x1, x2 shared,
    x3 per channel). Returns f_n, xi_n and P_n0, P_n1, ... (each channel's scale)."""
    f = np.asarray(f, dtype=float)
    sel = f > 0 if band is None else (f >= band[0]) & (f <= band[1]) & (f > 0)
    rows, rhs, scales, blocks = [], [], [], []
    m = len(amplitudes)
    for c, A in enumerate(amplitudes):
        A = np.abs(np.asarray(A))[sel]
        s = A.max()
        a = A / s
        W = TWO_PI * f[sel]
        pw = 3 if weighting == "A3" else 2
        cols = np.zeros((len(a), 2 + m))
        cols[:, 0], cols[:, 1] = a**pw, a**pw * W**2
        cols[:, 2 + c] = -(a if pw == 3 else np.ones_like(a))
        rows.append(cols)
        rhs.append(-(a**pw) * W**4)
        scales.append(s)
        blocks.append(a)
    M, b = np.vstack(rows), np.concatenate(rhs)
    x, *_ = np.linalg.lstsq(M, b, rcond=None)
    wn = x[0] ** 0.25
    xi = float(np.sqrt(x[1] / (4 * wn**2) + 0.5))
    params = {"f_n": wn / TWO_PI, "xi_n": xi}
    for c in range(m):
        params[f"P_n{c}"] = float(np.sqrt(max(x[2 + c], 0.0))) * scales[c]
    W = TWO_PI * f[sel]
    D = np.sqrt((wn**2 - W**2) ** 2 + (2 * wn * xi * W) ** 2)
    resid = np.concatenate([np.sqrt(max(x[2 + c], 0)) / D - blocks[c] for c in range(m)])
    target = np.concatenate(blocks)
    _, r2, nrmse = _stats(resid, target, None, list(params), x)
    return Fit(params, {k: float("nan") for k in params}, r2, nrmse, len(target),
               f"appendix D.2 global ({weighting})", modes=(("f_n", "xi_n"),)).checked(
                   resolution_hz=_spacing(f))


# ---- circle fitting and half-power bandwidth ----------------------------------------------
def circle_fit(f, H, band) -> Fit:
    """Circle fit of one mode (Kennedy-Pancu, as the GenRad's "circle fitting", §2.6):
    near resonance the mobility jωH traces a circle; the resonance is the point opposite
    the origin, f_n where the angle around the centre reaches it, and the damping the
    mean over point pairs (a below, b above) of
    η = (ω_b² - ω_a²)/(ω_n² (tan(θ_a/2) + tan(θ_b/2))), ξ = η/2."""
    f, H = np.asarray(f, dtype=float), np.asarray(H, dtype=complex)
    df = _spacing(f)
    sel = (f >= band[0]) & (f <= band[1]) & np.isfinite(H)
    f, Y = f[sel], 1j * TWO_PI * f[sel] * H[sel]
    if len(f) < 5:
        raise VtableError("circle fit needs at least 5 points in the band")
    x, y = Y.real, Y.imag
    A = np.column_stack([x, y, np.ones_like(x)])
    c, *_ = np.linalg.lstsq(A, x * x + y * y, rcond=None)  # Kasa algebraic fit
    centre = c[0] / 2 + 1j * c[1] / 2
    R = float(np.sqrt(c[2] + abs(centre) ** 2))
    ang = np.unwrap(np.angle(Y - centre))
    theta_n = float(np.angle(centre))  # the point opposite the origin
    theta_n += 2 * np.pi * np.round((np.mean(ang) - theta_n) / (2 * np.pi))
    w2 = (TWO_PI * f) ** 2
    order = np.argsort(ang) if ang[-1] > ang[0] else np.argsort(-ang)
    wn2 = float(np.interp(theta_n, ang[order] if ang[-1] > ang[0] else -ang[order],
                          w2[order]) if ang[-1] > ang[0] else
                np.interp(-theta_n, -ang[order], w2[order]))
    below, above = np.nonzero(w2 < wn2)[0], np.nonzero(w2 > wn2)[0]
    if len(below) < 1 or len(above) < 1:
        raise VtableError("circle fit: the band must straddle the resonance")
    etas = []
    for ja in below:
        for jb in above:
            ta, tb = abs(ang[ja] - theta_n), abs(ang[jb] - theta_n)
            if 0.1 < ta < 2.5 and 0.1 < tb < 2.5:
                etas.append((w2[jb] - w2[ja]) / (wn2 * (np.tan(ta / 2) + np.tan(tb / 2))))
    if not etas:
        raise VtableError("circle fit: too few points on the circle around the resonance")
    eta = np.array(etas)
    resid = np.abs(Y - centre) - R
    _, r2, nrmse = _stats(resid, np.abs(Y), None, ("f_n", "xi_n"), np.zeros(2))
    return Fit({"f_n": float(np.sqrt(wn2) / TWO_PI), "xi_n": float(np.mean(eta) / 2)},
               {"f_n": float(np.diff(f).mean() / 2),
                "xi_n": float(np.std(eta) / 2 / np.sqrt(len(eta)))},
               r2, nrmse, len(f), "circle fit", {"radius": R},
               modes=(("f_n", "xi_n"),)).checked(resolution_hz=df)


def half_power(f, A) -> Fit:
    """Half-power bandwidth: ξ = (f₂ - f₁)/(2 f_n), f₁, f₂ where |A| = max/√2
    (interpolated)."""
    f, A = np.asarray(f, dtype=float), np.abs(np.asarray(A))
    i = int(np.nanargmax(A))
    level = A[i] / np.sqrt(2)
    lo = np.nonzero(A[:i] < level)[0]
    hi = np.nonzero(A[i:] < level)[0]
    if len(lo) == 0 or len(hi) == 0:
        raise VtableError("half-power points are outside the data")
    j, k = lo[-1], i + hi[0]
    f1 = float(np.interp(level, [A[j], A[j + 1]], [f[j], f[j + 1]]))
    f2 = float(np.interp(level, [A[k], A[k - 1]], [f[k], f[k - 1]]))
    fn = float(f[i])
    df = float(np.diff(f).mean())
    return Fit({"f_n": fn, "xi_n": (f2 - f1) / (2 * fn)}, {"f_n": df / 2,
                                                           "xi_n": df / (2 * fn)},
               float("nan"), float("nan"), int(k - j + 1), "half-power bandwidth",
               {"f1": f1, "f2": f2}, modes=(("f_n", "xi_n"),)).checked(resolution_hz=df)
