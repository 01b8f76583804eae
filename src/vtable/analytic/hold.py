"""A linear system stepped exactly with its input linear over each step (first-order hold):
the one discretisation the reduced model, the controllers, the spectra and the interaction
studies share.

For ẋ = A x + B u with u(t) = u_k + (u_{k+1} − u_k) (t − t_k)/h on [t_k, t_k + h],

    x_{k+1} = Φ x_k + Γ u_k + Λ (u_{k+1} − u_k),

Φ = e^{Ah}, Γ = ∫₀ʰ e^{Aτ} dτ B, Λ = (1/h) ∫₀ʰ e^{Aτ} (h − τ) dτ B, read off one matrix
exponential (Van Loan 1978): exp([[A, B, 0], [0, 0, I], [0, 0, 0]] h) holds Φ, Γ and h Λ
in its first block row. The augmented matrix is balanced first (`balance`): a state in
pascals beside one in metres would otherwise set the exponential's norm, and its
squarings, by the units."""

from __future__ import annotations

import numpy as np
import scipy.linalg


def balance(A: np.ndarray, separate: bool = False):
    """`scipy.linalg.matrix_balance(A, permute=False, separate=separate)`: LAPACK's
    diagonal scaling alone. SciPy casts every factor to an integer to read the
    permutations it does not make here; a factor beyond an integer's range (a state whose
    row is nearly zero: a rocking stiffness of 1e-300 lb·in/rad in a model file) made that
    cast warn on the user's terminal about a value never used."""
    with np.errstate(invalid="ignore"):
        return scipy.linalg.matrix_balance(A, permute=False, separate=separate)


def first_order_hold(A: np.ndarray, B: np.ndarray, h: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Φ, Γ, Λ) of the module docstring for step `h` (s).

    Parameters
    ----------
    A
        (n, n) state matrix.
    B
        (n, m) input matrix, or (n,) for one input (Γ and Λ are then (n,)).
    h
        The step.

    Returns
    -------
    tuple
        Φ (n, n), Γ and Λ (n, m) or (n,), C-contiguous.
    """
    A = np.asarray(A, dtype=float)
    one = np.ndim(B) == 1
    B = np.asarray(B, dtype=float)
    B = B[:, None] if one else B
    n, m = B.shape
    M = np.zeros((n + 2 * m, n + 2 * m))
    M[:n, :n], M[:n, n:n + m] = A * h, B * h
    M[n:n + m, n + m:] = np.eye(m)  # u grows by (u_{k+1} - u_k) over the step
    Mb, (scale, _) = balance(M, separate=True)
    E = scipy.linalg.expm(Mb) * scale[:, None] / scale[None, :]
    phi, gam, lam = E[:n, :n], E[:n, n:n + m], E[:n, n + m:]
    if one:
        gam, lam = gam[:, 0], lam[:, 0]
    return (np.ascontiguousarray(phi), np.ascontiguousarray(gam),
            np.ascontiguousarray(lam))
