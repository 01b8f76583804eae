"""Is a fitted number a fact? The flags every fit carries, computed by one function.

A fit is flagged (machine-readable `code`, the parameter it concerns, a one-line `text`)
when

- ``at_bound``: a parameter ended on a bound of the optimiser (the data did not fix it);
- ``not_finite``: a parameter is NaN or infinite (e.g. appendix D's ξ² < 0, eq D.11);
- ``stderr_large``: its standard error exceeds its magnitude;
- ``no_stderr``: its standard error is NaN or infinite (the method gives none);
- ``correlated``: two parameters correlated beyond `CORRELATION_MAX` (from the
  covariance σ²(JᵀJ)⁻¹): only a combination of them is determined, each alone is not
  (an over-damped loop: f_o and ξ_o);
- ``poor_fit``: R² < `R2_MIN`: the model explains too little of the fitted quantity;
- ``low_coherence``: the mean coherence γ² of the fitted lines is below `COHERENCE_MIN`;
- ``unresolved``: a damping whose half-power band 2ξf holds fewer than
  `frames.LINES_PER_BAND` lines of the estimate (see `vtable.ident.frames`);
- ``few_averages`` / ``one_average``: the transfer function averaged fewer than
  `frames.MIN_AVERAGES` frames (with one, the coherence is 1 by construction).

A number derived from a flagged fit (the gain margin of eq 6.20 from eq 6.15's fit, the
springs of eqs 5.4-5.5 from flagged frequencies) carries the flags with `source` set:
`inherit`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, Protocol

from vtable.ident.frames import LINES_PER_BAND, MIN_AVERAGES

#: below this R² the fitted model does not describe the data it was fitted to
R2_MIN = 0.9
#: below this mean γ² over the fitted lines, noise or nonlinearity dominates them
COHERENCE_MIN = 0.8
#: above this |ρ| two parameters are not determined separately
CORRELATION_MAX = 0.995
#: a parameter within this fraction of a bound (relative to the bound) is on it
BOUND_TOLERANCE = 1e-3

#: a short marker for the printed tables, by flag code
MARKERS = {"at_bound": "at bound", "not_finite": "no value", "stderr_large": "σ > value",
           "no_stderr": "no σ", "unresolved": "unresolved", "correlated": "correlated"}

SYMBOLS = {"f_o": "f_o", "xi_o": "ξ_o", "k_o": "k_o", "f_s": "f_s", "xi_s": "ξ_s",
           "f_n": "f_n", "xi_n": "ξ_n", "gain": "gain", "P_n": "P_n"}


class FitLike(Protocol):
    """What the flags are computed from (`vtable.ident.fits.Fit` is one)."""

    params: dict[str, float]
    stderr: dict[str, float]
    r2: float
    bounds: dict[str, tuple[float, float]]
    modes: tuple[tuple[str, str], ...]
    context: dict[str, float]
    correlation: dict[str, float]
    flags: tuple[Flag, ...]


@dataclass(frozen=True)
class Flag:
    """Why a number is not a plain fact: a code, the parameter (None: the whole fit),
    one line of text, and the fit it came from when inherited."""

    code: str
    text: str
    param: str | None = None
    source: str | None = None

    def to_json(self) -> dict[str, Any]:
        return {"code": self.code, "param": self.param, "text": self.text,
                "source": self.source}


def _sym(name: str) -> str:
    return SYMBOLS.get(name, name)


def fit_flags(fit: FitLike) -> tuple[Flag, ...]:
    """All flags of a fit, from its parameters, standard errors, bounds, goodness of fit
    and its context (`resolution_hz`, `averages`, `coherence`: the mean γ² of the fitted
    lines), in a fixed order."""
    out: list[Flag] = []
    for k, v in fit.params.items():
        s = _sym(k)
        if not math.isfinite(v):
            out.append(Flag("not_finite", f"{s}: the fit gives no finite value", k))
            continue
        lo, hi = fit.bounds.get(k, (-math.inf, math.inf))
        for b, side in ((lo, "lower"), (hi, "upper")):
            if math.isfinite(b) and abs(v - b) <= BOUND_TOLERANCE * max(abs(b), 1e-12):
                out.append(Flag("at_bound", f"{s} = {v:.4g} is at its {side} bound {b:g}: "
                                "the data do not determine it", k))
        e = fit.stderr.get(k, math.nan)
        if not math.isfinite(e):
            out.append(Flag("no_stderr", f"{s}: no standard error", k))
        elif e > abs(v):
            out.append(Flag("stderr_large", f"{s} = {v:.4g} ± {e:.2g}: the standard error "
                            "exceeds the value", k))
    for pair, rho in fit.correlation.items():
        a, b = pair.split(",")
        if abs(rho) > CORRELATION_MAX:
            for k in (a, b):
                out.append(Flag("correlated", f"{_sym(k)}: correlated {rho:+.4f} with "
                                f"{_sym(b if k == a else a)}: only a combination of the two "
                                "is determined", k))
    df = fit.context.get("resolution_hz")
    if df is not None and math.isfinite(df) and df > 0:
        for fk, xk in fit.modes:
            f, xi = fit.params.get(fk, math.nan), fit.params.get(xk, math.nan)
            if not (math.isfinite(f) and math.isfinite(xi)):
                continue
            band = 2 * abs(xi) * f
            lines = band / df
            if lines < LINES_PER_BAND:
                out.append(Flag(
                    "unresolved", f"{_sym(xk)}: resolution {df:.3g} Hz vs the half-power band "
                    f"2ξf = {band:.3g} Hz ({lines:.1f} lines, {LINES_PER_BAND} needed): the "
                    "damping is not resolved", xk))
    if math.isfinite(fit.r2) and fit.r2 < R2_MIN:
        out.append(Flag("poor_fit", f"R² {fit.r2:.3f} < {R2_MIN}: the model does not describe "
                        "the data"))
    coh = fit.context.get("coherence")
    if coh is not None and math.isfinite(coh) and coh < COHERENCE_MIN:
        out.append(Flag("low_coherence", f"mean coherence {coh:.2f} < {COHERENCE_MIN} over the "
                        "fitted lines"))
    n = fit.context.get("averages")
    if n is not None:
        if n <= 1:
            out.append(Flag("one_average", "one average: the coherence is 1 by construction and "
                            "says nothing; the estimate has no averaging"))
        elif n < MIN_AVERAGES:
            out.append(Flag("few_averages", f"{int(n)} averages (< {MIN_AVERAGES}): large random "
                            "error"))
    return tuple(out)


def settled(fit: FitLike, params: Iterable[str]) -> bool:
    """Whether `params` of the fit are good enough to choose frames from: no flag on
    them other than ``unresolved`` (which the new frames address), and no ``poor_fit``."""
    keep = set(params)
    return not any((f.param in keep and f.code != "unresolved") or f.code == "poor_fit"
                   for f in fit.flags)


#: a steady sine has max|x|/rms(x) = √2; above this the motion is not steady cycles
STEADY_CREST_MAX = 1.6


def loop_flags(crest_factor: float, f_hz: float) -> list[Flag]:
    """The loop measures ξ_v and C (eqs 5.12-5.13) count cycles at f_hz and take the
    largest excursion as the amplitude: exact for steady cycles only."""
    if math.isfinite(crest_factor) and crest_factor <= STEADY_CREST_MAX:
        return []
    return [Flag("not_steady", f"ξ_v and C assume steady cycles at {f_hz:.3g} Hz; this motion "
                 f"has peak/RMS {crest_factor:.2f} (a sine {math.sqrt(2):.2f}): loop measures "
                 "of a random motion, not a damping ratio")]


def inherit(flags: Iterable[Flag], source: str, params: Iterable[str] | None = None,
            whole_fit: bool = True) -> list[Flag]:
    """The flags a derived number takes from the fit `source`: all of them, or those of
    `params` and (unless `whole_fit` is False) the whole-fit ones."""
    keep = None if params is None else set(params)
    return [Flag(f.code, f"{source}: {f.text}", None, source) for f in flags
            if keep is None or f.param in keep or (f.param is None and whole_fit)]


def flags_json(flags: Iterable[Flag]) -> list[dict[str, Any]]:
    return [f.to_json() for f in flags]


def marker(flags: Iterable[Flag], param: str) -> str:
    """' ⚠ at bound, unresolved' for the printed tables, '' when the parameter is clean."""
    m = [MARKERS.get(f.code, f.code) for f in flags if f.param == param]
    return f" ⚠ {', '.join(dict.fromkeys(m))}" if m else ""
