"""A linear reduced model's outputs stepped in its modal coordinates: only the channels and
the samples a fit needs (`ModalOutputs.outputs`).

A linear model (no force element, no quadratic damper, every hydraulic stage linear) is the
state-space system ẏ = A y + B x_c of `reduced_kernel.linear_system`. With A = V Λ V⁻¹ (A
balanced first: pressures in Pa beside displacements in m), the modal coordinates
z = V⁻¹ y step independently under the same first-order hold as `simulate_linear`,
z_{k+1} = e^{λh} z_k + γ₀ x_k + γ₁ (x_{k+1} − x_k), γ₀ = (e^{λh} − 1)/λ,
γ₁ = (e^{λh} − 1 − λh)/(λ²h) (times V⁻¹B), and each channel of `ReducedModel.simulate` is a
row c·y + d x_c (its `_channels` is linear in the histories), read only at the samples
asked (`reduced_kernel.simulate_modal`). The same values as `simulate` to rounding, at a
fraction of its cost; an unstable or ill-conditioned model is simulated whole.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from vtable._numba import first_compile
from vtable.analytic.hold import balance
from vtable.interpolate import upsampled
from vtable.models.reduced_kernel import simulate_modal
from vtable.models.reduced_parts import kept_histories


def filtered(filters: Sequence[tuple[Callable, frozenset | None]],
             out: dict[str, np.ndarray], fs: float) -> dict[str, np.ndarray]:
    """The channels `out` (sampled at `fs`) through the model's output filters, each
    (fn(x, fs), the channels it applies to or None: all) in turn, in place: each distinct
    signal once, zeros left as they are; a read-only one (kept histories') handed to a
    filter as a copy, which the filter may change in place."""
    for fn, only in filters:
        done: dict[int, np.ndarray] = {}
        for k, v in out.items():
            if only is not None and k not in only:
                continue
            if id(v) not in done:
                done[id(v)] = fn(v if v.flags.writeable else v.copy(), fs) if np.any(v) \
                    else v
            out[k] = done[id(v)]
    return out


class ModalOutputs:
    """`ReducedModel`'s fast outputs (the module docstring); it provides `simulate`,
    `histories`, `linear`, `_linear` (A, B, f_y, f_u), `element` (None: structure only,
    `simulate` says so), `M`, `max_step`, `assembly`, `_channels`, `_aliased`, and what
    `reduced_parts.kept_histories` reads (`integrated`, `pe`, `elem`, `python`, `ne`)."""

    def outputs(self, t: np.ndarray, x_c: np.ndarray, names: Sequence[str],
                step: int = 1) -> dict[str, np.ndarray]:
        """The channels `names` (those of `simulate`) at every `step`-th sample of `t`
        (the same values as `simulate`'s, to rounding). A linear model computes only these
        (`reduced_kernel.simulate_modal`: the modal coordinates stepped exactly, the output
        rows of `_output_map`); any other is integrated whole, and its channels computed
        from the histories at the samples asked when no output filter needs them all."""
        fast = self._modal() if self.linear and self.element is not None else None
        if fast is None:
            if self.assembly.filters:  # a filter reads the whole signal: those asked only
                return self._filtered_outputs(t, x_c, names, step)
            # the channels are linear in the histories, sample by sample
            _h, up, _xc, Q, Qd, Qdd, F, PL = self.histories(t, x_c)
            k = up * step
            full = self._aliased(self._channels(Q[::k], Qd[::k], Qdd[::k], F[::k], PL[::k]))
            return {c: full[c] for c in names if c in full}
        alias = self._aliases(tuple(names))
        names = list(dict.fromkeys(alias.values()))  # a lumped quantity once
        t = np.asarray(t, dtype=float)
        dt = float((t[-1] - t[0]) / (len(t) - 1)) if len(t) > 1 else 0.0
        if not dt > 0:
            self.histories(t, x_c)  # its one-line error
        up = max(1, math.ceil(dt / self.max_step - 1e-9))
        h = dt / up
        xc = upsampled(x_c, len(t), up)
        filters = self.assembly.filters
        every = 1 if filters else up * step
        phi, g0, g1, Cm, D = self._modal_step(h, tuple(names))
        with first_compile(simulate_modal):
            Y = simulate_modal(xc, phi, g0, g1, Cm, D, every)
        out = {c: Y[i] for i, c in enumerate(names)}
        if filters:
            out = {c: v[::up * step] for c, v in filtered(filters, out, 1.0 / h).items()}
        return {c: out[a] for c, a in alias.items()}

    def _filtered_outputs(self, t: np.ndarray, x_c: np.ndarray, names: Sequence[str],
                          step: int) -> dict[str, np.ndarray]:
        """`outputs` of a model stepped whole with output filters: `simulate`'s channels
        `names` (the same values), only the histories' channels they read filtered (a
        fit's targets read 7 of the 10 a friction model's filter would run on), the
        histories kept by the model's dynamics (`reduced_parts.kept_histories`: a fit that
        moves only the filters' parameters steps them once)."""
        h, up, _xc, Q, Qd, Qdd, F, PL = kept_histories(self, t, x_c)
        raw = self._channels(Q, Qd, Qdd, F, PL)
        source = self._aliased({k: k for k in raw})  # each channel -> the one it reads
        keys = {source[c] for c in names if c in source}
        out = filtered(self.assembly.filters, {k: v for k, v in raw.items() if k in keys},
                       1.0 / h)
        once = {k: out[k][::up * step] for k in keys}  # a lumped quantity once
        return {c: once[source[c]] for c in names if c in source}

    def _aliases(self, names: tuple[str, ...]) -> dict[str, str]:
        """Each of `names` the model predicts -> the first of them with the same output row
        (a lumped quantity several channels stand for is computed once)."""
        cache = self.__dict__.setdefault("_alias_of", {})
        if names not in cache:
            rows = self._output_map()
            have = [c for c in names if c in rows]
            cache[names] = {c: next(a for a in have if rows[a][0] is rows[c][0])
                            for c in have}
        return cache[names]

    def _modal_step(self, h: float, names: tuple[str, ...]):
        """(e^{λh}, γ₀, γ₁, output rows, feedthrough) of `simulate_modal` for step `h` and
        the channels `names` (kept: the runs of a campaign share them): the first-order
        hold of each mode, γ₀ = (e^{λh} − 1)/λ and γ₁ = (e^{λh} − 1 − λh)/(λ²h) times
        V⁻¹B (their series where λh is tiny), the rows times V with each conjugate pair
        once, doubled. The other of each pair (λ below the real axis) is left out: its
        rows weigh nothing, and stepping it was work for nothing."""
        key = (h, names)
        cache = self.__dict__.setdefault("_steps", {})
        if key not in cache:
            lam, V, Vinv = self._modal()
            rows = self._output_map()
            lh = lam * h
            phi = np.exp(lh)
            small = np.abs(lh) < 1e-6
            with np.errstate(divide="ignore", invalid="ignore"):
                g0 = np.where(small, h * (1 + lh / 2), (phi - 1) / np.where(small, 1, lam))
                g1 = np.where(small, h * (0.5 + lh / 6),
                              (phi - 1 - lh) / np.where(small, 1, lam * lam * h))
            bt = Vinv @ self._linear[1]
            weight = np.where(lam.imag > 0, 2.0, np.where(lam.imag < 0, 0.0, 1.0))
            Cm = (np.array([rows[c][0] for c in names]) @ V * weight if names
                  else np.zeros((0, len(lam)), dtype=complex))
            D = np.array([rows[c][1] for c in names]) if names else np.zeros(0)
            kept = weight != 0.0  # every value as with the whole set, the pairs' others out
            cache[key] = (phi[kept], (g0 * bt)[kept], (g1 * bt)[kept],
                          np.ascontiguousarray(Cm[:, kept]), D)
        return cache[key]

    def _modal(self):
        """(λ, V, V⁻¹) of the linear model's A when its modal coordinates can be stepped
        (eigenvectors well conditioned, no eigenvalue in the right half-plane: an unstable
        model is stepped by `simulate_linear`, which ends it with NaN as the others do);
        else None."""
        if not hasattr(self, "_modal_"):
            A = self._linear[0]
            self._modal_ = None
            try:  # pressures (Pa) beside displacements (m): balanced first
                _, (s, _) = balance(A, separate=True)
                lam, Vb = np.linalg.eig(A * (s[None, :] / s[:, None]))
                if np.all(np.isfinite(lam)) and lam.real.max() < 0 and \
                        np.linalg.cond(Vb) < 1e8:
                    self._modal_ = (lam, Vb * s[:, None], np.linalg.inv(Vb) / s[None, :])
            except (np.linalg.LinAlgError, ValueError):
                pass
        return self._modal_

    def _output_map(self) -> dict[str, tuple[np.ndarray, float]]:
        """Each channel of `simulate` (before its output filters) as (c, d): the channel is
        c·y + d x_c in the linear model's state y (`_channels` is linear in q, q̇, q̈, F
        and P_L, each of them linear in y and x_c: applied to the unit states and the unit
        command it gives the rows)."""
        if not hasattr(self, "_rows"):
            A, B, fy, fu = self._linear
            ny, nq = A.shape[0], self.M.shape[0]
            E = np.vstack([np.eye(ny), np.zeros((1, ny))])  # unit states, then x_c = 1
            Q, Qd = E[:, :nq], E[:, nq:2 * nq]
            Qdd = np.vstack([A[nq:2 * nq].T, B[nq:2 * nq][None, :]])
            F = np.append(fy, fu)
            PL = E[:, 2 * nq].copy()
            out = self._aliased(self._channels(Q, Qd, Qdd, F, PL))
            rows: dict[int, tuple[np.ndarray, float]] = {}  # one row per distinct array
            self._rows = {c: rows.setdefault(id(v), (np.ascontiguousarray(v[:ny]),
                                                     float(v[ny])))
                          for c, v in out.items()}
        return self._rows

