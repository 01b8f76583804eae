"""Which structure the servo loop x_t/x_c has, and its parameters (report ch. 6).

Candidates, each fitted to the complex H1 of x_t over x_c (real and imaginary parts):

- ``eq_6_15``: eq 6.15b, (f_o, ξ_o, k_o): the valve-integrator loop of ch. 6, type 1;
- ``eq_6_15_lag``: eq 6.15b with a first-order servovalve lag τ in the loop
  (`vtable.ident.fits.h_open_loop_lag`), (f_o, ξ_o, k_o, τ), type 1;
- ``declared``: the run's declared digital controller (`vtable.controllers.kinds`) closed
  around the platen (`vtable.analytic.controlled`, eq 6.15 generalised), (f_o, ξ_o, k_o, τ)
  with the controller's own terms as declared, type 1 — a candidate when the table
  declares such a controller (`Prior.declared`);
- ``resonator``: eq 7.9 with the valve lag (`vtable.ident.resonator`), (f_o, ξ_o, k_o, τ,
  f_s, ξ_s, u): a resonance on the platen the run does not declare, type 1 — kept only
  when it beats every other structure's AIC by `AIC_MARGIN` and `is_resonance`;
- ``type_0``: a type-0 second-order loop K ω_n²/(s² + 2ζω_n s + ω_n²), (K, f_n, ζ): a
  plant without an integrator (an electrodynamic shaker under proportional control).

Weights: the H1 estimate of a line has a random error of about ε|H| per part, with
ε = √(1 - γ²)/(|γ|√(2 n_d)) (Bendat & Piersol, as in `vtable.ident.frames`), floored
at `EPS_MIN`; each residual is divided by it, so that χ² compares structures on the
data's own scale. The structures are compared by Akaike's criterion
AIC = n ln(χ²/n) + 2p over the n = 2 x lines real numbers.

The DC gain: a valve-integrator loop follows a static command exactly (type 1, DC gain
1); `dc_gain` measures it from the lowest resolved lines alone (|H| extrapolated to
ω -> 0 by a short series in ω², `dc_window`), with a standard error from the lines'
random errors and scatter plus the extrapolation's own, and no model of the loop: a loop
whose |H| rises to a low-frequency peak (a PI controller, feedforward) is judged below
the peak, not through a structure that cannot follow it. A record without two resolved
lines has its DC gain not judged, with a note. The loop is *not* eq 6.15 when g
differs from 1 (|g - 1| > max(3σ_g, `DC_TOL`)) or when the type-0 structure's AIC is
lower than both type-1 structures' by more than `AIC_MARGIN`; then its eq 6.15
parameters are not quoted, and the structure that fits is named.

With ``delay=True`` every structure carries a pure delay e^{jωΔ} (Δ > 0: the input
leads the output by Δ beyond the loop's own lag): the lag of a drive file played by the
controller (`vtable.runs.drive`), estimated jointly with the loop.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vtable.analytic.controlled import declared_loop
from vtable.errors import VtableError
from vtable.ident.fits import (
    Fit,
    _least_squares,
    _select,
    h_open_loop,
    h_open_loop_lag,
    h_resonator_lag,
    h_type0,
    phase_crossover,
)
from vtable.ident.resonator import dip, is_resonance
from vtable.ident.tf import TransferFunction
from vtable.params.loops import OpenLoop
from vtable.tables.lab import bare_loop

TWO_PI = 2 * np.pi
#: the smallest relative random error a line is credited with (model error, bias of a
#: coherence estimated from a few averages)
EPS_MIN = 2e-3
#: AIC difference that counts as one structure fitting better than another
AIC_MARGIN = 10.0
#: a DC gain within this of 1 is a type-1 loop whatever its standard error
DC_TOL = 0.03
#: the DC gain's lines start at this bin of the frame (bin 1's Hann main lobe reaches
#: the DC bin, which each frame's mean removal empties)
DC_FIRST_BIN = 2
#: the DC gain's window: the lowest lines whose |H| is within this of the lowest line's
DC_SPAN = 0.05
#: ... and at least this many lines
DC_MIN_LINES = 4
#: a type-1 fit whose residuals are more than this many times the lines' random errors
#: (`misfit`) is noted as describing the loop only roughly
MISFIT_NOTE = 5.0
#: the delays scanned for a start (s, relative to the coarse alignment)
DELAY_SCAN = (-0.5, 1.0)


@dataclass(frozen=True)
class Structure:
    """A candidate loop model: its name, parameters, bounds and frequency response."""

    key: str
    name: str
    params: tuple[str, ...]
    h: Callable[..., np.ndarray]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    type1: bool
    modes: tuple[tuple[str, str], ...]


STRUCTURES: dict[str, Structure] = {
    "eq_6_15": Structure("eq_6_15", "eq 6.15", ("f_o", "xi_o", "k_o"), h_open_loop,
                         (0.1, 1e-3, 0.1), (1000.0, 10.0, 1e4), True, (("f_o", "xi_o"),)),
    "eq_6_15_lag": Structure("eq_6_15_lag", "eq 6.15 with a first-order valve lag",
                             ("f_o", "xi_o", "k_o", "tau"), h_open_loop_lag,
                             (0.1, 1e-3, 0.1, 0.0), (1000.0, 10.0, 1e4, 1.0), True,
                             (("f_o", "xi_o"),)),
    "resonator": Structure("resonator", "eq 7.9 with a valve lag: a resonator on the "
                           "platen the run does not declare",
                           ("f_o", "xi_o", "k_o", "tau", "f_s", "xi_s", "u"), h_resonator_lag,
                           (0.1, 1e-3, 0.1, 0.0, 0.2, 1e-3, 1e-3),
                           (1000.0, 10.0, 1e4, 1.0, 200.0, 1.0, 20.0), True,
                           (("f_o", "xi_o"), ("f_s", "xi_s"))),
    "type_0": Structure("type_0", "a type-0 second-order loop", ("gain", "f_n", "zeta"),
                        h_type0, (1e-3, 0.05, 1e-3), (100.0, 1000.0, 10.0), False,
                        (("f_n", "zeta"),)),
}


@dataclass(frozen=True)
class Prior:
    """What the table's description predicts for the loop (eq 6.16 and the valve's time
    constant): starting values for the fits and, for a record that cannot resolve the
    loop, the loop the drive's lag is estimated with."""

    open_loop: OpenLoop
    tau: float
    source: str
    #: the table's declared controller as a structure (`declared_structure`), if any
    declared: Structure | None = None
    #: the largest mass ratio a resonator on the platen can have: the table's payload over
    #: its platen mass (None: no payload declared)
    u_max: float | None = None


def declared_structure(vt) -> Structure:
    """The structure of a table's declared controller (`vtable.analytic.controlled`):
    x_t/x_c with (f_o, ξ_o, k_o, τ) free and the controller's terms as declared."""
    return Structure("declared", "the declared controller's loop (eq 6.15 generalised)",
                     ("f_o", "xi_o", "k_o", "tau"), declared_loop(vt),
                     (0.1, 1e-3, 0.1, 0.0), (1000.0, 10.0, 1e4, 1.0), True,
                     (("f_o", "xi_o"),))


def prior_of(table) -> Prior:
    """What a run's table (`vtable.runs.lab.run_table`) predicts of its loop: eq 6.16,
    its valve time constant and its declared controller's structure."""
    declared = declared_structure(table) if table.control is not None \
        else None
    u_max = table.payload / table.platen_mass if table.payload else None
    return Prior(bare_loop(table), table.valve_lag, table.name, declared, u_max)


@dataclass(frozen=True)
class LoopData:
    """The lines of an H1 estimate a loop is fitted to: f, H, their random errors σ
    (per real and imaginary part) and the fit context (resolution, coherence,
    averages); `low`, the same estimate's lines from its lowest resolved one up (below
    the fitting band too), which the DC gain is measured on (`dc_gain`)."""

    f: np.ndarray
    H: np.ndarray
    sigma: np.ndarray
    context: dict[str, float]
    low: LoopData | None = None

    @classmethod
    def from_tf(cls, tf: TransferFunction, band: tuple[float, float],
                min_coherence: float = 0.9) -> LoopData:
        f, H, w, ctx = _select(tf.f, tf.H, tf.coherence, band, min_coherence)
        ctx = {**ctx, "averages": float(tf.averages)}
        low = None
        first = DC_FIRST_BIN * tf.resolution_hz * (1 - 1e-9)
        try:
            fl, Hl, wl, _ = _select(tf.f, tf.H, tf.coherence, (first, band[1]), min_coherence)
            low = cls(fl, Hl, _sigma(Hl, wl, tf.averages), ctx)
        except VtableError:
            pass
        return cls(f, H, _sigma(H, w, tf.averages), ctx, low)


def _sigma(H: np.ndarray, w: np.ndarray, averages: int) -> np.ndarray:
    """The random error ε|H| of H1 lines with coherence w² from `averages` averages,
    ε = √(1 - γ²)/(|γ|√(2 n_d)) floored at `EPS_MIN`."""
    g2 = np.clip(w**2, 1e-12, 1.0)
    eps = np.sqrt((1 - g2) / (g2 * 2 * max(averages, 1)))
    return np.abs(H) * np.maximum(eps, EPS_MIN)


def _resid(st: Structure, data: LoopData, delay: bool, gain: bool):
    """Weighted residuals (real and imaginary parts) of a structure; the parameter
    vector is the structure's, then the free gain, then the delay."""
    n = len(st.params)
    s = 1j * TWO_PI * data.f

    def fun(x):
        h = st.h(data.f, *x[:n])
        if gain:
            h = h * x[n]
        if delay:
            h = h * np.exp(s * x[-1])
        r = (h - data.H) / data.sigma
        return np.concatenate([r.real, r.imag])

    return fun


def _scan_delay(st: Structure, data: LoopData, x0: list[float], dt: float) -> float:
    """The delay (s) that best aligns the structure at `x0` with the data: the weighted
    cost over a grid of delays (quarter-sample steps in `DELAY_SCAN`)."""
    h = st.h(data.f, *x0)
    grid = np.arange(DELAY_SCAN[0], DELAY_SCAN[1], dt / 4)
    cost = np.empty(len(grid))
    s = 1j * TWO_PI * data.f
    for i in range(0, len(grid), 256):
        d = grid[i:i + 256, None]
        r = (h[None, :] * np.exp(s[None, :] * d) - data.H[None, :]) / data.sigma[None, :]
        cost[i:i + 256] = np.sum(np.abs(r) ** 2, axis=1)
    return float(grid[int(np.argmin(cost))])


def _starts(st: Structure, data: LoopData, prior: Prior | None) -> list[list[float]]:
    """Starting points: the table's described loop (when given) and one read off the
    data (f_o at the 180° phase crossing, ξ_o 0.5, k_o from eq 6.19; for the type-0
    loop K from the lowest lines, f_n at the 90° crossing, ζ from the peak)."""
    out: list[list[float]] = []
    if st.type1:
        if prior is not None:
            ol = prior.open_loop
            x = [ol.f_o, max(ol.xi_o, 0.02), ol.k_o]
            out.append([*x, max(prior.tau, 0.001)] if len(st.params) == 4 else x)
        try:
            f0 = phase_crossover(data.f, data.H)
            h0 = float(np.interp(f0, data.f, np.abs(data.H)))
            k0 = max(2 * 0.5 * TWO_PI * f0 * h0 / (1 + h0), 1.0)
            x = [f0, 0.5, k0]
            out.append([*x, 0.001] if len(st.params) == 4 else x)
        except VtableError:
            pass
        if not out:
            x = [float(data.f[-1]), 0.5, TWO_PI * float(data.f[-1]) / 4]
            out.append([*x, 0.001] if len(st.params) == 4 else x)
    else:
        k0 = float(np.mean(np.abs(data.H[:3])))
        ph = np.unwrap(np.angle(data.H))
        below = np.nonzero(ph <= -np.pi / 2)[0]
        fn0 = float(data.f[below[0]]) if len(below) else float(data.f[-1])
        z0 = float(np.clip(k0 / (2 * np.interp(fn0, data.f, np.abs(data.H))), 0.05, 2.0))
        out.append([k0, fn0, z0])
        if prior is not None:
            out.append([k0, prior.open_loop.f_o, 0.5])
    if len(st.params) == 7:  # the resonator: at the deepest dip of |H| and on a grid
        x = out[0]
        grid = [dip(data), *np.geomspace(0.5, 0.8 * float(data.f[-1]), 8)]
        out = [[*x[:3], x[3] if len(x) == 4 else 0.001, f_s0, 0.05, u0]
               for f_s0 in grid for u0 in (0.2, 1.0)]
    lo, hi = np.array(st.lower), np.array(st.upper)
    return [list(np.clip(x, lo * (1 + 1e-6) + 1e-12, hi * (1 - 1e-6))) for x in out]


def structures(prior: Prior | None) -> dict[str, Structure]:
    """The candidate structures: `STRUCTURES`, and the declared controller's when the
    prior has one."""
    if prior is not None and prior.declared is not None:
        return {**STRUCTURES, "declared": prior.declared}
    return STRUCTURES


def fit_structure(key: str, data: LoopData, prior: Prior | None = None,
                  delay_dt: float | None = None, gain: bool = False,
                  start: Fit | None = None) -> Fit:
    """One structure fitted to the data by bounded nonlinear least squares from each
    starting point (`_starts`, or `start`'s parameters), the best kept. `delay_dt` (the
    sampling step, s) adds a free delay "delay" started from a scan; `gain` a free DC
    gain "gain" (the lag structure only)."""
    st = structures(prior)[key]
    names = list(st.params)
    lo, hi = list(st.lower), list(st.upper)
    if "u" in names and prior is not None and prior.u_max:  # no heavier than the payload
        hi[names.index("u")] = min(hi[names.index("u")], prior.u_max)
    if gain:
        names, lo, hi = [*names, "gain"], [*lo, 0.001], [*hi, 100.0]
    if delay_dt is not None:
        names, lo, hi = [*names, "delay"], [*lo, DELAY_SCAN[0] - 0.5], [*hi, DELAY_SCAN[1] + 0.5]
    if start is not None:
        starts = [[start.params[k] for k in st.params]]
    else:
        starts = _starts(st, data, prior)
    fun = _resid(st, data, delay_dt is not None, gain)
    best: Fit | None = None
    for x0 in starts:
        x = list(x0)
        if gain:
            x.append(start.params.get("gain", 1.0) if start is not None else 1.0)
        if delay_dt is not None:
            x.append(start.params["delay"] if start is not None and "delay" in start.params
                     else _scan_delay(st, data, list(x0), delay_dt))
        x = list(np.clip(x, np.array(lo) + 1e-12, np.array(hi) - 1e-12))
        target = np.concatenate([(data.H / data.sigma).real, (data.H / data.sigma).imag])
        fit = _least_squares(fun, x, lo, hi, tuple(names), target,
                             f"{st.name} complex fit", st.modes, data.context,
                             xtol=1e-12, ftol=1e-12)
        if best is None or fit.extra["cost"] < best.extra["cost"]:
            best = fit
    assert best is not None
    return best


def misfit(fit: Fit) -> float:
    """√(χ²/ν) of a weighted complex fit: its residuals in units of the lines' random
    errors (about 1 for a structure that holds the loop)."""
    return math.sqrt(2 * fit.extra["cost"] / max(fit.n_points - len(fit.params), 1))


def aic(fit: Fit) -> float:
    """Akaike's criterion n ln(χ²/n) + 2p of a weighted complex fit."""
    n = fit.n_points
    chi2 = max(2 * fit.extra["cost"], 1e-300)
    return n * math.log(chi2 / n) + 2 * len(fit.params)


@dataclass(frozen=True)
class LoopStructure:
    """The candidate structures fitted to one H1 estimate, compared, and the verdict."""

    fits: dict[str, Fit]
    aic: dict[str, float]
    best: str
    dc_gain: Fit
    fits_eq_6_15: bool
    why: str
    delay: bool = False
    notes: tuple[str, ...] = field(default=())
    #: the structures compared (`structures`: the declared controller's too, if any)
    candidates: dict[str, Structure] = field(default_factory=lambda: dict(STRUCTURES))
    rejected: Fit | None = None  # the resonator's fit left out: no resonance found

    @property
    def dc(self) -> tuple[float, float]:
        """The DC gain and its standard error."""
        return self.dc_gain.params["gain"], self.dc_gain.stderr["gain"]

    def best_type1(self) -> str:
        return min((k for k in self.fits if self.candidates[k].type1),
                   key=self.aic.__getitem__)

    def to_json(self) -> dict[str, Any]:
        g, sg = self.dc
        return {"fits_eq_6_15": self.fits_eq_6_15, "best": self.best,
                "best_name": self.candidates[self.best].name, "why": self.why,
                "dc_gain": g, "dc_gain_stderr": sg, "dc_gain_how": self.dc_gain.method,
                "candidates": {k: {"name": self.candidates[k].name,
                                   "type1": self.candidates[k].type1, "aic": self.aic[k],
                                   "delta_aic": self.aic[k] - self.aic[self.best],
                                   **f.to_json()} for k, f in self.fits.items()},
                "criterion": f"AIC = n ln(χ²/n) + 2p on the complex H1 weighted by its random "
                             f"error; a structure is better by more than {AIC_MARGIN:g}",
                "notes": list(self.notes)}


def dc_window(data: LoopData) -> int:
    """How many of the lowest lines the DC gain is read from: those whose |H| stays
    within `DC_SPAN` of the lowest line's (contiguous from it), at least `DC_MIN_LINES`.
    |H|, not H: a delay between command and response (a drive file not aligned) leaves
    it unchanged."""
    m = np.abs(data.H)
    inside = np.abs(m / m[0] - 1) <= DC_SPAN
    n = int(np.argmin(inside)) if not inside.all() else len(m)
    return min(max(n, DC_MIN_LINES), len(m))


def _poly_fit(w2: np.ndarray, m: np.ndarray, sig: np.ndarray,
              order: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Weighted least squares of m = Σ c_k (ω²)^k, k < order: the coefficients, their
    covariance (scaled by χ²/ν when that exceeds 1) and χ²/ν."""
    A = np.vander(w2, order, increasing=True) / sig[:, None]
    y = m / sig
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ coef
    dof = len(m) - order
    chi2_red = float(r @ r) / dof if dof > 0 else 1.0
    return coef, np.linalg.pinv(A.T @ A) * max(chi2_red, 1.0), chi2_red


def dc_gain(data: LoopData) -> Fit:
    """The DC gain g: |H| extrapolated to ω -> 0 from the lowest resolved lines.

    Near ω = 0, |H(jω)|² of any rational loop is a series in ω², so on the lowest lines
    (`dc_window`, from `LoopData.low`) |H| = g + b ω² + c ω⁴ is fitted by weighted least
    squares, each line weighted by its H1 random error ε|H| (ε² = (1 - γ²)/(2 n_d γ²),
    Bendat & Piersol) and the covariance scaled by χ²/ν when the lines scatter more than
    their random errors say. g's standard error adds to that statistical one the
    extrapolation's own: the change in g when the ω⁴ term is dropped (how far the
    series is from converged on these lines). No model of the loop enters, so a loop
    whose response rises to a low-frequency peak is measured below it whatever its
    structure. Fewer than 2 lines: g = NaN, n_points 0."""
    lines = data.low if data.low is not None else data
    if len(lines.f) < 2:
        return Fit({"gain": float("nan")}, {"gain": float("nan")}, float("nan"),
                   float("nan"), 0, "DC gain: no lines")
    n = dc_window(lines)
    f, m, sig = lines.f[:n], np.abs(lines.H[:n]), lines.sigma[:n]
    w2 = (TWO_PI * f) ** 2
    if n < 4:
        (g, _), cov, chi2_red = _poly_fit(w2, m, sig, 2)
        g2, how = g, "g + bω²"
    else:
        (g, *_), cov, chi2_red = _poly_fit(w2, m, sig, 3)
        (g2, _), *_ = _poly_fit(w2, m, sig, 2)
        how = "g + bω² + cω⁴"
    stat = float(np.sqrt(cov[0, 0]))
    sg = float(np.hypot(stat, g - g2))
    return Fit({"gain": float(g)}, {"gain": sg}, float("nan"), float("nan"), n,
               f"DC gain: |H| = {how} on the {n} lowest lines, {f[0]:.3g}-{f[-1]:.3g} Hz",
               {"chi2_red": chi2_red, "stat": stat, "extrapolation": float(abs(g - g2)),
                "f_low_hz": float(f[0]), "f_high_hz": float(f[-1])})


def compare_structures(data: LoopData, prior: Prior | None = None,
                       delay_dt: float | None = None) -> LoopStructure:
    """Fit the three structures (and the DC gain) to the data and say whether the loop
    is a valve-integrator loop of eq 6.15 (module docstring)."""
    cands = structures(prior)
    fits = {k: fit_structure(k, data, prior, delay_dt) for k in cands}
    crit = {k: aic(f) for k, f in fits.items()}
    others = {k: a for k, a in crit.items() if k != "resonator"}
    rejected = None
    if "resonator" in crit and not (crit["resonator"] + AIC_MARGIN < min(others.values())
                                    and is_resonance(fits["resonator"])):
        cands = {k: v for k, v in cands.items() if k != "resonator"}  # no resonance found
        rejected, crit = fits.pop("resonator"), others
    best = min(crit, key=crit.__getitem__)
    ones = [k for k in cands if cands[k].type1]
    type1 = min(crit[k] for k in ones)
    reasons, notes = [], []
    dc = dc_gain(data)
    g, sg = dc.params["gain"], dc.stderr["gain"]
    measured = dc.n_points > 0
    if not measured:
        notes.append("DC gain not measured: fewer than 2 resolved lines with the coherence "
                     "required")
    elif not math.isfinite(sg) or abs(g - 1) > max(3 * sg, DC_TOL):
        reasons.append(f"its DC gain is {g:.3f} ± {sg:.2g}, not 1: a valve-integrator "
                       "(type-1) loop follows a static command exactly")
    type0_better = crit["type_0"] + AIC_MARGIN < type1
    if type0_better:
        reasons.append(f"{STRUCTURES['type_0'].name} fits better (AIC lower by "
                       f"{type1 - crit['type_0']:.0f}): its phase tends to -180°, not to the "
                       "-270° of a valve-integrator loop")
    ok = not reasons
    t1 = min(ones, key=crit.__getitem__)
    spread = misfit(fits[t1])
    if ok and spread > MISFIT_NOTE:
        notes.append(f"{cands[t1].name} leaves residuals {spread:.0f}x the lines' random "
                     f"errors (R² {fits[t1].r2:.4f}): x_t/x_c holds dynamics it does not "
                     "model (a specimen, another controller), and its parameters describe "
                     "the loop only roughly")
    if ok:
        margin = min((a - crit[best] for k, a in crit.items() if k != best), default=0.0)
        dc_text = f"DC gain {g:.3f} ± {sg:.2g}" if measured else "DC gain not measured"
        why = (f"a valve-integrator loop: {dc_text}; best structure "
               f"{cands[best].name}" +
               ("" if margin > AIC_MARGIN else
                f" (the record hardly tells the structures apart: AIC within {margin:.0f})"))
    else:
        fit_note = (f"; {cands[best].name} fits (R² {fits[best].r2:.4f})"
                    if not cands[best].type1 else "; no candidate structure fits")
        why = "x_t/x_c does not fit eq 6.15: " + "; ".join(reasons) + fit_note
    return LoopStructure(fits, crit, best, dc, ok, why, delay_dt is not None, tuple(notes),
                         dict(cands), rejected)


def fit_delay_held(data: LoopData, prior: Prior, delay_dt: float) -> Fit:
    """The delay alone, with the loop held at the table's description (eq 6.16 and its
    valve time constant, `prior`): for a record whose lines do not tell the candidate
    structures apart (their AICs within `AIC_MARGIN`), where a delay fitted jointly
    would trade against the loop's own lag."""
    ol = prior.open_loop
    st = prior.declared or STRUCTURES["eq_6_15_lag"]
    h = st.h(data.f, ol.f_o, ol.xi_o, ol.k_o, prior.tau)
    s = 1j * TWO_PI * data.f
    x0 = _scan_delay(st, data, [ol.f_o, ol.xi_o, ol.k_o, prior.tau], delay_dt)

    def fun(x):
        r = (h * np.exp(s * x[0]) - data.H) / data.sigma
        return np.concatenate([r.real, r.imag])

    target = np.concatenate([(data.H / data.sigma).real, (data.H / data.sigma).imag])
    lo, hi = DELAY_SCAN[0] - 0.5, DELAY_SCAN[1] + 0.5
    return _least_squares(fun, [x0], [lo], [hi], ("delay",), target,
                          f"the loop of {prior.source} (eq 6.16, valve lag {prior.tau:g} s) "
                          "held", (), data.context, xtol=1e-12, ftol=1e-12)


def resolved(ls: LoopStructure) -> bool:
    """Whether the record tells the structures apart: the best one's fit is unflagged and
    its AIC lower than every other's by more than `AIC_MARGIN`."""
    others = [a for k, a in ls.aic.items() if k != ls.best]
    return ls.fits[ls.best].ok and all(a - ls.aic[ls.best] > AIC_MARGIN for a in others)
