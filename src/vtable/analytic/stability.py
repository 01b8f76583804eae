"""Stability by Routh-Hurwitz on the characteristic polynomial (eqs 6.11, 7.10).

The characteristic polynomial is computed with the Faddeev-LeVerrier recursion (no
eigenvalues), on a scaled matrix, so this check is independent of `LinearModel.poles`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def characteristic_polynomial(A: np.ndarray) -> np.ndarray:
    """Coefficients of det(sI - A), highest power first (leading 1).

    Faddeev-LeVerrier on A/σ with σ = ||A||₁, rescaled: coefficient of s^k is σ^(n-k) ĉ_k.
    """
    A = np.asarray(A, dtype=float)
    n = A.shape[0]
    sigma = float(np.linalg.norm(A, 1)) or 1.0
    As = A / sigma
    c = np.zeros(n + 1)
    c[0] = 1.0
    M = np.zeros_like(As)
    eye = np.eye(n)
    for k in range(1, n + 1):
        M = As @ M + c[k - 1] * eye
        c[k] = -np.trace(As @ M) / k
    return c * sigma ** np.arange(n + 1)


@dataclass(frozen=True)
class RouthResult:
    """Routh array outcome: stable iff every first-column entry is positive."""

    stable: bool
    first_column: np.ndarray
    sign_changes: int  # = number of roots in the right half plane


def routh_hurwitz(coeffs: np.ndarray, eps: float = 1e-12) -> RouthResult:
    """Routh array of a polynomial (highest power first).

    A zero leading entry in a row is replaced by eps·scale (the ε method); a whole zero
    row (roots symmetric about the origin) is marginal and reported as not stable.
    """
    a = np.trim_zeros(np.asarray(coeffs, dtype=float), "f")
    if a[0] < 0:
        a = -a
    n = len(a) - 1
    scale = np.max(np.abs(a))
    width = n // 2 + 1
    rows = [np.zeros(width), np.zeros(width)]
    rows[0][: len(a[0::2])] = a[0::2]
    rows[1][: len(a[1::2])] = a[1::2]
    marginal = False
    for _ in range(2, n + 1):
        r1, r2 = rows[-2], rows[-1]
        if np.all(np.abs(r2) <= eps * scale):
            marginal = True
            r2 = r2.copy()
            r2[0] = eps * scale
            rows[-1] = r2
        pivot = r2[0] if abs(r2[0]) > eps * scale else eps * scale
        new = np.zeros(width)
        new[:-1] = (pivot * r1[1:] - r1[0] * r2[1:]) / pivot
        rows.append(new)
    first = np.array([r[0] for r in rows[: n + 1]])
    signs = np.sign(np.where(np.abs(first) <= eps * scale, eps, first))
    changes = int(np.sum(signs[1:] != signs[:-1]))
    return RouthResult(stable=bool(changes == 0 and not marginal and np.all(first > 0)),
                       first_column=first, sign_changes=changes)
