"""One state-space API for every analytical model of the report.

A `LinearModel` is ẋ = A x + B u, y = C x + D u with named states, inputs and outputs
(SI units). Frequencies at the interface are in Hz.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.signal

from vtable.analytic.hold import balance
from vtable.analytic.margins import Margins, loop_margins, open_loop_from_closed
from vtable.analytic.stability import RouthResult, characteristic_polynomial, routh_hurwitz
from vtable.errors import UnstableError, VtableError

TWO_PI = 2 * np.pi


@dataclass(frozen=True)
class Mode:
    """An oscillatory eigen-pair: f = |λ|/2π (eq 9.3), ξ = -Re λ/|λ| (eq 9.4)."""

    f_hz: float
    damping: float
    eigenvalue: complex


@dataclass(frozen=True)
class Modes:
    """Eigen-modes of A (eq 9.1): oscillatory pairs by frequency, and real roots (1/s)."""

    oscillatory: tuple[Mode, ...]
    real_roots: tuple[float, ...]

    @property
    def first(self) -> Mode:
        """The lowest-frequency oscillatory mode (the first coupled mode, §9.3)."""
        if not self.oscillatory:
            raise VtableError("the model has no oscillatory mode")
        return self.oscillatory[0]


def modes_of(eigenvalues: np.ndarray, tol: float = 1e-9) -> Modes:
    """Split eigenvalues into oscillatory modes (eqs 9.2-9.4) and real roots."""
    lam = np.asarray(eigenvalues, dtype=complex)
    scale = np.maximum(np.abs(lam), 1.0)
    osc = [z for z in lam if z.imag > tol * max(abs(z), 1.0)]
    real = sorted((z.real for z, s in zip(lam, scale, strict=True) if abs(z.imag) <= tol * s),
                  reverse=False)
    modes = sorted((Mode(abs(z) / TWO_PI, -z.real / abs(z), complex(z)) for z in osc),
                   key=lambda m: m.f_hz)
    return Modes(tuple(modes), tuple(float(r) for r in real))


def _residues(CV: np.ndarray, VB: np.ndarray) -> np.ndarray:
    """The residue of every output/input pair at every pole, K[n, (p, m)] = CV[p, n] VB[n, m],
    laid out so that H(s) - D = (1/(s - λ)) @ K for all frequencies in one product."""
    return (CV.T[:, :, None] * VB[:, None, :]).reshape(CV.shape[1], -1)


class LinearModel:
    """ẋ = A x + B u, y = C x + D u with named states, inputs and outputs."""

    def __init__(self, A, B, C, D, *, states: Sequence[str], inputs: Sequence[str],
                 outputs: Sequence[str], title: str = "") -> None:
        self.A = np.asarray(A, dtype=float)
        self.B = np.asarray(B, dtype=float).reshape(self.A.shape[0], -1)
        self.C = np.asarray(C, dtype=float).reshape(-1, self.A.shape[0])
        self.D = np.asarray(D, dtype=float).reshape(self.C.shape[0], self.B.shape[1])
        self.states, self.inputs, self.outputs = tuple(states), tuple(inputs), tuple(outputs)
        if len(self.states) != self.A.shape[0] or len(self.inputs) != self.B.shape[1] \
                or len(self.outputs) != self.C.shape[0]:
            raise ValueError("names do not match the matrix shapes")
        self.title = title or type(self).__name__

    # -- construction helper ------------------------------------------------------------
    @classmethod
    def _build(cls, A, B, states, inputs, outputs: Mapping[str, tuple], title: str = "",
               **kw) -> dict:
        """Matrices from output definitions name -> (c_row, d_row) (d_row may be None)."""
        n, m = np.shape(A)[0], np.shape(B)[1] if np.ndim(B) == 2 else 1
        C = np.zeros((len(outputs), n))
        D = np.zeros((len(outputs), m))
        for i, (c, d) in enumerate(outputs.values()):
            C[i] = c
            if d is not None:
                D[i] = d
        return dict(A=A, B=B, C=C, D=D, states=states, inputs=inputs,
                    outputs=tuple(outputs), title=title, **kw)

    def _index(self, name: str | None, names: tuple[str, ...], kind: str) -> int | slice:
        if name is None:
            return slice(None)
        try:
            return names.index(name)
        except ValueError:
            raise VtableError(f"{self.title} has no {kind} {name!r}; "
                              f"expected one of {', '.join(names)}") from None

    # -- frequency domain ---------------------------------------------------------------
    def freqresp(self, f_hz, output: str | None = None, input: str | None = None) -> np.ndarray:
        """H(j2πf) = C (j2πf I - A)⁻¹ B + D on many frequencies at once (eqs 8.21-8.24).

        With `output` and `input` named: a complex array shaped like f_hz; otherwise an
        array (n_f, n_outputs, n_inputs).

        Evaluated in modal form, H = (C V) diag(1/(s - λ)) (V⁻¹ B) + D: every frequency
        and output/input pair in one matrix product (n operations per value). Where the
        modal sum could have lost more than ~1e-11 of a value to rounding (estimated from
        cond(V) and the size of the cancelling terms; e.g. an acceleration output at low
        frequency), and whenever A is defective, those frequencies are solved directly
        (LU of sI - A, as python-control does without slycot), so the result agrees with
        a direct solve to ~1e-10.
        """
        f = np.asarray(f_hz, dtype=float)
        s = 1j * TWO_PI * f.ravel()
        oi = self._index(output, self.outputs, "output")
        ii = self._index(input, self.inputs, "input")
        B = self.B[:, ii].reshape(self.A.shape[0], -1)
        C = self.C[oi].reshape(-1, self.A.shape[0])
        D = self.D[oi, ii].reshape(C.shape[0], B.shape[1])
        H = np.empty((len(s), C.shape[0], B.shape[1]), dtype=complex)
        todo = np.ones(len(s), dtype=bool)
        modal = self._modal()
        if modal is not None:
            lam, V, Vinv, cond, t = modal  # A = T V Λ V⁻¹ T⁻¹ with T = diag(t)
            CV, VB = (C * t) @ V, Vinv @ (B / t[:, None])
            R = 1.0 / (s[:, None] - lam)  # (n_f, n)
            # one product for every frequency and pair: H[f, (p, m)] = Σ_n R[f, n] K[n, (p, m)]
            K = _residues(CV, VB)
            H = (R @ K).reshape(H.shape) + D
            size = (np.abs(R) @ _residues(np.abs(CV), np.abs(VB))).reshape(H.shape) + np.abs(D)
            bound = 1e-15 * max(cond, 1.0) * size
            todo = np.any(bound > 1e-11 * np.abs(H), axis=(1, 2))
        if np.any(todo):
            st = s[todo]
            M = st[:, None, None] * np.eye(self.A.shape[0]) - self.A
            X = np.linalg.solve(M, np.broadcast_to(B, (len(st), *B.shape)))
            H[todo] = C @ X + D
        if output is not None and input is not None:
            return H[:, 0, 0].reshape(f.shape)
        return H

    def _modal(self):
        """Cached eigen-decomposition of the balanced A (LAPACK gebal scaling, which
        brings cond(V) from ~1e4 to ~10 for these models), or None when A is (nearly)
        defective."""
        key = self.A.tobytes()
        cached = getattr(self, "_modal_cache", None)
        if cached is None or cached[0] != key:
            Ab, T = balance(self.A)
            lam, V = np.linalg.eig(Ab)
            cond = float(np.linalg.cond(V))
            data = (lam, V, np.linalg.inv(V), cond, np.diag(T).copy()) if cond < 1e8 else None
            cached = (key, data)
            self._modal_cache = cached
        return cached[1]

    # -- eigen-structure and stability --------------------------------------------------
    def poles(self) -> np.ndarray:
        """Eigenvalues of A (1/s)."""
        return np.linalg.eigvals(self.A)

    def modes(self) -> Modes:
        """Frequencies and damping ratios (eqs 9.1-9.4) plus real roots."""
        return modes_of(self.poles())

    def is_stable(self) -> bool:
        """Every eigenvalue strictly in the left half plane."""
        return bool(np.all(self.poles().real < 0))

    def unstable_poles(self) -> np.ndarray:
        p = self.poles()
        return p[p.real >= 0]

    def check_stable(self) -> None:
        """Raise `UnstableError` naming the offending eigenvalues."""
        bad = self.unstable_poles()
        if len(bad):
            raise UnstableError(self.title, bad)

    def characteristic_polynomial(self) -> np.ndarray:
        return characteristic_polynomial(self.A)

    def routh_hurwitz(self) -> RouthResult:
        """Routh-Hurwitz test on det(sI - A) (eqs 6.11, 7.10 in general form)."""
        return routh_hurwitz(self.characteristic_polynomial())

    def margins(self, output: str = "x_t", input: str = "x_c", f_min: float = 1e-3,
                f_max: float = 1e3) -> Margins:
        """Gain and phase margins of L = H/(1-H) with H = output/input (§6.8, §7.7)."""
        self.check_stable()
        return loop_margins(lambda f: open_loop_from_closed(self.freqresp(f, output, input)),
                            f_min, f_max)

    # -- time domain --------------------------------------------------------------------
    def response(self, t, u, x0=None) -> dict[str, np.ndarray]:
        """Outputs for input histories on a uniform time grid (first-order hold).

        `u` is an array (n_t,) for a single-input model, (n_t, n_inputs), or a mapping
        input name -> history (missing inputs are zero).
        """
        t = np.asarray(t, dtype=float)
        if isinstance(u, Mapping):
            unknown = set(u) - set(self.inputs)
            if unknown:
                raise VtableError(f"{self.title} has no input {sorted(unknown)[0]!r}; "
                                  f"expected {', '.join(self.inputs)}")
            U = np.zeros((len(t), len(self.inputs)))
            for k, v in u.items():
                U[:, self.inputs.index(k)] = v
        else:
            U = np.asarray(u, dtype=float).reshape(len(t), -1)
            if U.shape[1] != len(self.inputs):
                raise VtableError(f"{self.title}: {U.shape[1]} input columns for inputs "
                                  f"{', '.join(self.inputs)}")
        sys = scipy.signal.StateSpace(self.A, self.B, self.C, self.D)
        _, y, x = scipy.signal.lsim(sys, U if U.shape[1] > 1 else U[:, 0], t, X0=x0)
        y = np.asarray(y).reshape(len(t), -1)
        out = {name: y[:, i] for i, name in enumerate(self.outputs)}
        out.update({f"state:{name}": x[:, i] for i, name in enumerate(self.states)})
        return out

    # -- interop ------------------------------------------------------------------------
    def to_control(self):
        """The same system as a python-control `StateSpace` (needs `pip install control`)."""
        try:
            import control  # an optional dependency (vtable[control])
        except ImportError:
            raise VtableError("python-control is not installed: pip install 'vtable[control]'")\
                from None
        return control.ss(self.A, self.B, self.C, self.D, states=list(self.states),
                          inputs=list(self.inputs), outputs=list(self.outputs),
                          name=re.sub(r"[^0-9A-Za-z_]+", "_", self.title).strip("_"))

    def __repr__(self) -> str:
        return (f"<{type(self).__name__} {self.title!r}: {len(self.states)} states, "
                f"inputs {self.inputs}, outputs {self.outputs}>")
