"""The Jacobian the diagnosis's least-squares fits use: forward differences where they must,
rank-one (Broyden) updates in between.

A forward-difference Jacobian of the reduced model's residuals costs one simulation of every
run per parameter (a dozen or more) at every iteration of `scipy.optimize.least_squares`;
the residual's own evaluation costs one. Between two iterations the Jacobian changes little:
Broyden's update J ← J + (Δr − J Δx) Δxᵀ / (Δxᵀ Δx) (Dennis & Schnabel, *Numerical Methods
for Unconstrained Optimization*, §8.1) makes it agree with the last step's change of the
residual at no cost, and the trust region of `least_squares` ('trf') keeps a step honest
when it is not exact. The Jacobian is taken by forward differences again every `REFRESH`
iterations, and always where the fit ends (`at`), for the Gauss-Newton covariance the fit's
flags read (`vtable.diagnose.statistics.correlations`).

Forward differences as `least_squares`' '2-point' takes them: steps of `diff_step` ×
max(1, |x_i|), turned back where they would leave the bounds.

`Secant.solve` hands `least_squares` the problem compacted to n + 1 rows (`compact`): with
[f J] = B R (B orthonormal, m × (n + 1); R upper triangular), the residual Bᵀf =
(‖f‖, 0, …, 0) and the Jacobian BᵀJ = R[:, 1:] give the same cost ½‖f‖², gradient Jᵀf and
Gauss-Newton matrix JᵀJ as f and J, so every step of 'trf' (its trust region solved by the
SVD of the Jacobian) is the same: to rounding, and to ~1e-8 relative in a direction the
columns nearly share (`GRAM_LIMIT`). It costs an (n + 1)-column Gram matrix instead of an
SVD of all m rows at every iteration (the README campaign's fits have 9,000-18,500
residual rows: in a sampling profile of its diagnosis, 9 % of the time went to those SVDs
and 2 % to the products with the whole Jacobian).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import scipy.linalg
import scipy.optimize

#: iterations between two forward-difference Jacobians (the first is one)
REFRESH = 4
#: `compact` takes R from the Cholesky factor of [f J]'s Gram matrix unless a column's part
#: independent of the columns before it is below this share of its norm (the factor's
#: relative error there is ~1e-16 / share²: 1e-8 at the limit), then from a QR
GRAM_LIMIT = 1e-4


def compact(f: np.ndarray, J: np.ndarray) -> np.ndarray:
    """Bᵀ J, (n + 1) × n, for [f J] = B R (B m × (n + 1) orthonormal, R upper triangular with
    a non-negative diagonal): R's columns after the first. With Bᵀ f = (‖f‖, 0, …, 0) it keeps
    ‖f‖, Jᵀ f and JᵀJ (the module docstring). R is the Cholesky factor of the Gram matrix
    of [f J] (its (n + 1)² products, not a decomposition of its m rows), or a QR's when
    that factor would lose digits (`GRAM_LIMIT`) or does not exist (f = 0, a column zero)."""
    n = J.shape[1]
    G = np.empty((n + 1, n + 1))
    G[0, 0] = f @ f
    G[0, 1:] = G[1:, 0] = f @ J
    G[1:, 1:] = J.T @ J
    try:
        R = scipy.linalg.cholesky(G, check_finite=False)
        if np.all(np.diag(R) > GRAM_LIMIT * np.sqrt(np.diag(G))):
            return R[:, 1:]
    except np.linalg.LinAlgError:
        pass
    R = scipy.linalg.qr(np.column_stack([f, J]), mode="r", check_finite=False)[0][:n + 1]
    R = R * np.where(np.diag(R) < 0, -1.0, 1.0)[:, None]
    if len(R) < n + 1:  # fewer rows than columns: the rest zero
        R = np.vstack([R, np.zeros((n + 1 - len(R), n + 1))])
    return R[:, 1:]


class Secant:
    """`fun` (x -> residuals) and a `jac` for `scipy.optimize.least_squares` that takes
    forward differences every `refresh` calls and Broyden updates in between; `evals`
    counts the residual evaluations."""

    def __init__(self, fun: Callable[[np.ndarray], np.ndarray], lo: np.ndarray,
                 hi: np.ndarray, diff_step: float = 1e-4, refresh: int = REFRESH) -> None:
        self._fun, self.lo, self.hi = fun, lo, hi
        self.diff_step, self.refresh = diff_step, refresh
        self._seen: dict[bytes, np.ndarray] = {}
        self._J: np.ndarray | None = None
        self._x: np.ndarray | None = None
        self._f: np.ndarray | None = None
        self._calls = 0
        self.evals = 0
        self._fd: tuple[bytes, np.ndarray] | None = None  # the last `jac` taken by differences

    def fun(self, x: np.ndarray) -> np.ndarray:
        f = self._fun(x)
        self.evals += 1
        if len(self._seen) > 8:
            self._seen.pop(next(iter(self._seen)))
        self._seen[np.asarray(x, dtype=float).tobytes()] = f
        return f

    def _value(self, x: np.ndarray) -> np.ndarray:
        f = self._seen.get(np.asarray(x, dtype=float).tobytes())
        return self.fun(x) if f is None else f

    def at(self, x: np.ndarray, cols=None) -> np.ndarray:
        """The forward-difference Jacobian at `x` (only the columns `cols`, the others
        zero, when given)."""
        x = np.asarray(x, dtype=float)
        f0 = self._value(x)
        J = np.zeros((len(f0), len(x)))
        for i in range(len(x)) if cols is None else cols:
            h = self.diff_step * max(1.0, abs(x[i])) * (1.0 if x[i] >= 0 else -1.0)
            if not self.lo[i] <= x[i] + h <= self.hi[i]:
                h = -h
            xi = x.copy()
            xi[i] += h
            J[:, i] = (self.fun(xi) - f0) / h
        return J

    def at_end(self, x: np.ndarray) -> np.ndarray:
        """`at(x)`, or the forward-difference Jacobian `jac` last took there (a fit whose
        every Jacobian is taken by differences ends where it took its last one)."""
        x = np.asarray(x, dtype=float)
        if self._fd is not None and self._fd[0] == x.tobytes():
            return self._fd[1].copy()
        return self.at(x)

    def solve(self, x0: np.ndarray, **kw) -> scipy.optimize.OptimizeResult:
        """`scipy.optimize.least_squares` ('trf') from `x0` with this `jac`, on the problem
        compacted to n + 1 rows (`compact`: the same steps, without an SVD of every row at
        each); `kw` its options (bounds, tolerances, max_nfev; the linear loss only). The
        result's `fun`, `jac` and `cost` are the whole residual's, at its `x`."""
        if kw.get("method", "trf") != "trf" or kw.get("loss", "linear") != "linear":
            raise ValueError("Secant.solve takes method='trf' with the linear loss only")
        x0 = np.asarray(x0, dtype=float)
        n = len(x0)
        last: list = [None]  # the last point `jac` was asked at: (x, f, J) in full

        def fun(x: np.ndarray) -> np.ndarray:
            f = self.fun(x)
            out = np.zeros(n + 1)
            out[0] = math.sqrt(float(f @ f))
            return out

        def jac(x: np.ndarray) -> np.ndarray:
            J = self.jac(x)  # (its residual at x: `_f`; its differences may have pushed
            f = self._f      # x out of those `_value` keeps)
            last[0] = (np.asarray(x, dtype=float).copy(), f, J)
            return compact(f, J)

        sol = scipy.optimize.least_squares(fun, x0, jac=jac, **kw)
        x, f, J = last[0]
        if not np.array_equal(x, sol.x):  # scipy's 'trf' ends where it last took the
            f, J = self._value(sol.x), self.at(sol.x)  # Jacobian; were it not to
        sol.fun, sol.jac, sol.cost = f, J, 0.5 * float(f @ f)
        return sol

    def seed(self, x: np.ndarray, J: np.ndarray) -> None:
        """Start from the Jacobian `J` at `x` (Broyden's updates from there)."""
        self._J, self._x, self._f = J, np.asarray(x, dtype=float).copy(), self._value(x)
        self._calls = 1

    def jac(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        f = self._value(x)
        if self._J is None or self._calls % self.refresh == 0:
            J = self.at(x)
            self._fd = (x.tobytes(), J)  # never changed in place: a Broyden step copies it
        else:
            J = self._J.copy()
            dx = x - self._x
            dd = float(dx @ dx)
            if dd > 0:
                J += np.outer(f - self._f - J @ dx, dx / dd)
        self._calls += 1
        self._J, self._x, self._f = J, x.copy(), f
        return J


class Families:
    """Forward-difference Jacobians shared by a fit's starts (`TableModel`'s rivals), one
    per family (starts with the same servo loop: as fitted, or as declared), taken in full
    at the family's first start. A later start of the family takes from there the columns
    of every parameter but `own` (the effect's), and forward differences for those: one
    simulation each, where a Jacobian of its own costs one per parameter (the starts near
    the fitted loop share its sensitivities as `projected`'s share the current model's;
    Broyden's updates carry each start on from its seed)."""

    def __init__(self, own: np.ndarray) -> None:
        self.own = np.asarray(own, dtype=int)
        self._J: dict = {}

    def seed(self, secant: Secant, x: np.ndarray, family) -> None:
        """Seed `secant` at `x` with its family's Jacobian (the family's first: its own,
        in full, as `least_squares`' first `jac` would take it)."""
        J0 = self._J.get(family)
        if J0 is None:
            J = secant.at(x)
            self._J[family] = J.copy()
        else:
            J = J0.copy()
            J[:, self.own] = secant.at(x, self.own)[:, self.own]
        secant.seed(x, J)
