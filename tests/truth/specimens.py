"""Specimens on the platen: none, a rigid block, a SDOF frame (§2.4, Table 8.1) or an
n-storey shear building; and the lab's *declared* version of a specimen (`perturb`).

Heights are measured from the horizontal actuator line (the run format's convention,
29.7 in below the table top). Storey damping is classical: C = M Φ diag(2 ξ_i ω_i) Φᵀ M
with mass-normalised Φ (Chopra, Dynamics of Structures, §11.4: the modal damping matrix),
every fixed-base mode at the ratio `xi` or each at its own (`mode_xi`); or Rayleigh damping
C = α M + β K (Chopra §11.4.1), whose ratio in mode i is ξ_i = α/(2ω_i) + β ω_i/2, with
α, β fixed by two (frequency, ratio) pairs (`rayleigh`), or by ξ at modes 1 and 2 when
`damping="rayleigh"`. A run declares the ratio of every mode (a list).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy import linalg, optimize

from .constants import INCH, KIP, G
from .errors import TruthError

KINDS = ("none", "rigid", "sdof", "shear_building")


@dataclass(frozen=True)
class Specimen:
    """A specimen in the report's units (kip, in, Hz). Build it with `none`, `rigid`,
    `sdof` or `building`."""

    kind: str
    weights_kip: tuple[float, ...] = ()
    heights_in: tuple[float, ...] = ()
    storey_k_kip_in: tuple[float, ...] = ()  # storey stiffnesses (sdof, shear_building)
    xi: float = 0.0
    damping: str = "modal"  # "modal" | "rayleigh"
    inertia_kip_in_s2: float = 0.0  # rigid block: own pitch inertia about its c.g.
    mode_xi: tuple[float, ...] = ()  # one ratio per fixed-base mode (overrides xi)
    rayleigh: tuple[tuple[float, float], tuple[float, float]] | None = None  # (f Hz, ξ) x 2

    @property
    def n(self) -> int:
        """Number of dynamic masses (0 for none and rigid)."""
        return len(self.weights_kip) if self.kind in ("sdof", "shear_building") else 0

    @property
    def total_weight_kip(self) -> float:
        return float(sum(self.weights_kip))

    def masses(self) -> np.ndarray:
        return np.array(self.weights_kip) * KIP / G

    def heights(self) -> np.ndarray:
        return np.array(self.heights_in) * INCH

    def stiffness(self) -> np.ndarray:
        """Fixed-base stiffness matrix of the shear building (N/m)."""
        k = np.array(self.storey_k_kip_in) * KIP / INCH
        n = len(k)
        K = np.zeros((n, n))
        for j in range(n):
            K[j, j] += k[j]
            if j > 0:
                K[j - 1, j - 1] += k[j]
                K[j - 1, j] -= k[j]
                K[j, j - 1] -= k[j]
        return K

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Fixed-base circular frequencies (rad/s) and mass-normalised mode shapes."""
        M = np.diag(self.masses())
        w2, phi = linalg.eigh(self.stiffness(), M)
        return np.sqrt(w2), phi

    def frequencies_hz(self) -> list[float]:
        if self.n == 0:
            return []
        return [float(w / (2 * math.pi)) for w in self.modes()[0]]

    def rayleigh_coefficients(self) -> tuple[float, float]:
        """(α, β) of C = α M + β K with ξ(ω) = α/(2ω) + β ω/2 through the two pairs (or
        through modes 1 and 2 at `xi` for damping="rayleigh")."""
        if self.rayleigh is not None:
            (f1, x1), (f2, x2) = self.rayleigh
            w1, w2 = 2 * math.pi * f1, 2 * math.pi * f2
        else:
            w = self.modes()[0]
            w1, w2, x1, x2 = w[0], w[1], self.xi, self.xi
        a0, a1 = np.linalg.solve([[1 / (2 * w1), w1 / 2], [1 / (2 * w2), w2 / 2]], [x1, x2])
        return float(a0), float(a1)

    @property
    def is_rayleigh(self) -> bool:
        return self.rayleigh is not None or (self.damping == "rayleigh" and self.n >= 2)

    def modal_damping(self) -> np.ndarray:
        """The damping ratio of each fixed-base mode, from the bottom one up."""
        w = self.modes()[0]
        if self.is_rayleigh:
            a0, a1 = self.rayleigh_coefficients()
            return a0 / (2 * w) + a1 * w / 2
        if self.mode_xi:
            return np.array(self.mode_xi, dtype=float)
        return np.full(len(w), self.xi)

    def damping_matrix(self) -> np.ndarray:
        M = np.diag(self.masses())
        w, phi = self.modes()
        if self.is_rayleigh:
            a0, a1 = self.rayleigh_coefficients()
            return a0 * M + a1 * self.stiffness()
        return M @ phi @ np.diag(2 * self.modal_damping() * w) @ phi.T @ M

    def declared(self) -> dict:
        """The run format's [specimen] table for this specimen."""
        if self.kind == "none":
            return {"kind": "none"}
        if self.kind == "rigid":
            return {"kind": "rigid", "weight_kip": self.weights_kip[0],
                    "height_in": self.heights_in[0]}
        if self.kind == "sdof":
            return {"kind": "sdof", "weight_kip": self.weights_kip[0],
                    "height_in": self.heights_in[0],
                    "frequency_hz": self.frequencies_hz()[0], "damping": self.xi}
        damping = (self.xi if not (self.mode_xi or self.is_rayleigh)
                   else [float(x) for x in self.modal_damping()])
        return {"kind": "shear_building", "weights_kip": list(self.weights_kip),
                "heights_in": list(self.heights_in),
                "frequencies_hz": self.frequencies_hz(), "damping": damping}


def _positive(name: str, v: float) -> float:
    if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
        raise TruthError(f"specimen: {name} must be a positive number, got {v!r}")
    return float(v)


def none() -> Specimen:
    """The bare table."""
    return Specimen("none")


def rigid(weight_kip: float, height_in: float, inertia_kip_in_s2: float = 0.0) -> Specimen:
    """A rigid block of `weight_kip` with its c.g. `height_in` above the actuator line
    and its own pitch inertia about the c.g. (e.g. §2.5's 70.5 kip blocks: 48 x 21.5 in
    section -> m(48² + 21.5²)/12 ≈ 42 kip-in-s²)."""
    _positive("weight_kip", weight_kip)
    if inertia_kip_in_s2 < 0:
        raise TruthError("specimen: inertia_kip_in_s2 must be >= 0")
    return Specimen("rigid", (float(weight_kip),), (float(height_in),),
                    inertia_kip_in_s2=float(inertia_kip_in_s2))


def sdof(weight_kip: float, height_in: float, f_hz: float, xi: float) -> Specimen:
    """A SDOF structure (§2.4, Table 8.1: 68 kips at 219 in, 2.87 Hz, 1 %)."""
    m = _positive("weight_kip", weight_kip) * KIP / G
    k = m * (2 * math.pi * _positive("f_hz", f_hz)) ** 2
    if not 0 <= xi < 1:
        raise TruthError(f"specimen: xi must be in [0, 1), got {xi!r}")
    return Specimen("sdof", (float(weight_kip),), (float(height_in),),
                    (k / (KIP / INCH),), float(xi))


def building(weights_kip: list[float], heights_in: list[float],
             storey_k_kip_in: list[float] | None = None,
             frequencies_hz: list[float] | None = None, xi: float | list[float] = 0.02,
             damping: str = "modal",
             rayleigh: tuple[tuple[float, float], tuple[float, float]] | None = None
             ) -> Specimen:
    """An n-storey shear building, floors from the bottom. Give the storey stiffnesses
    (kip/in) or the n fixed-base frequencies (the stiffnesses are then solved for, from
    a uniform-stiffness start; an unreachable set of frequencies is an error).

    Damping: `xi` one ratio for every mode or a list (one per mode, from the bottom one);
    `rayleigh` ((f₁ Hz, ξ₁), (f₂ Hz, ξ₂)): C = α M + β K through those two pairs."""
    n = len(weights_kip)
    if n == 0 or len(heights_in) != n:
        raise TruthError(f"specimen: weights_kip and heights_in must have the same "
                         f"non-zero length, got {len(weights_kip)} and {len(heights_in)}")
    for w in weights_kip:
        _positive("weights_kip", w)
    if any(b <= a for a, b in itertools.pairwise(heights_in)):
        raise TruthError("specimen: heights_in must increase from the bottom floor up")
    if damping not in ("modal", "rayleigh"):
        raise TruthError(f"specimen: damping must be 'modal' or 'rayleigh', got {damping!r}")
    if (storey_k_kip_in is None) == (frequencies_hz is None):
        raise TruthError("specimen: give exactly one of storey_k_kip_in or frequencies_hz")
    mode_xi: tuple[float, ...] = ()
    if isinstance(xi, list | tuple):
        if len(xi) != n or not all(0 <= x < 1 for x in xi):
            raise TruthError(f"specimen: xi as a list needs {n} ratios in [0, 1), got {xi}")
        mode_xi, xi = tuple(float(x) for x in xi), float(xi[0])
    if rayleigh is not None:
        pairs = tuple((float(f), float(x)) for f, x in rayleigh)
        if (len(pairs) != 2 or pairs[0][0] == pairs[1][0]
                or not all(f > 0 and 0 < x < 1 for f, x in pairs)):
            raise TruthError(f"specimen: rayleigh needs two (frequency Hz > 0, ratio in (0, "
                             f"1)) pairs at different frequencies, got {rayleigh}")
        if mode_xi:
            raise TruthError("specimen: give xi as a list or rayleigh, not both")
        rayleigh, xi = pairs, pairs[0][1]
    base = Specimen("shear_building", tuple(map(float, weights_kip)),
                    tuple(map(float, heights_in)), (), float(xi), damping, mode_xi=mode_xi,
                    rayleigh=rayleigh)
    if storey_k_kip_in is not None:
        if len(storey_k_kip_in) != n:
            raise TruthError(f"specimen: storey_k_kip_in needs {n} values")
        return replace(base, storey_k_kip_in=tuple(_positive("storey_k_kip_in", k)
                                                   for k in storey_k_kip_in))
    if len(frequencies_hz) != n:
        raise TruthError(f"specimen: frequencies_hz needs {n} values (one per storey)")
    target = np.sort(np.array([_positive("frequencies_hz", f) for f in frequencies_hz]))

    def resid(logk):
        s = replace(base, storey_k_kip_in=tuple(np.exp(logk)))
        return np.log(np.array(s.frequencies_hz()) / target)

    k1 = replace(base, storey_k_kip_in=(1.0,) * n)
    scale = (target[0] / k1.frequencies_hz()[0]) ** 2
    sol = optimize.least_squares(resid, np.full(n, math.log(scale)), xtol=1e-14, ftol=1e-14)
    if np.max(np.abs(sol.fun)) > 1e-6:
        raise TruthError("specimen: no shear building with these weights has the fixed-base "
                         f"frequencies {list(target)} Hz (closest misses by "
                         f"{np.max(np.abs(sol.fun)):.1%}); give storey_k_kip_in instead")
    return replace(base, storey_k_kip_in=tuple(float(k) for k in np.exp(sol.x)))


def perturb(spec: Specimen, seed: int, frequency: float = 0.03, damping: float = 1.5,
            weight: float = 0.05, height: float = 0.0) -> Specimen:
    """What a lab would declare: each property moved by between half and all of its bound,
    with a random sign (seeded), so the declaration always differs from the truth.

    frequency: relative bound on the fixed-base frequencies (stiffnesses scale with it);
    damping: factor bound (ξ multiplied or divided by up to `damping`);
    weight, height: relative bounds.
    """
    rng = np.random.default_rng(seed)

    def rel(bound: float) -> float:
        return float(rng.choice([-1, 1]) * rng.uniform(0.5, 1.0) * bound)

    if spec.kind == "none":
        return spec
    w = tuple(x * (1 + rel(weight)) for x in spec.weights_kip)
    h = tuple(x * (1 + rel(height)) for x in spec.heights_in)
    if spec.kind == "rigid":
        return replace(spec, weights_kip=w, heights_in=h)
    xi = spec.xi * float(damping ** (rng.choice([-1, 1]) * rng.uniform(0.5, 1.0)))
    mode_xi: tuple[float, ...] = ()
    if spec.mode_xi or spec.is_rayleigh:
        # each mode's ratio moved on its own (the declaration is then a list, per mode)
        mode_xi = tuple(float(x * damping ** (rng.choice([-1, 1]) * rng.uniform(0.5, 1.0)))
                        for x in spec.modal_damping())
    df = rel(frequency)
    # stiffness follows the weight (same frequency) times the frequency change squared
    ratio = [wn / wo for wn, wo in zip(w, spec.weights_kip, strict=True)]
    k = tuple(kk * ratio[j] * (1 + df) ** 2 for j, kk in enumerate(spec.storey_k_kip_in))
    if spec.kind == "shear_building":
        k = tuple(kk * (1 + 0.3 * rel(frequency)) for kk in k)  # a little shape change too
    if mode_xi:
        return replace(spec, weights_kip=w, heights_in=h, storey_k_kip_in=k, xi=mode_xi[0],
                       mode_xi=mode_xi, rayleigh=None, damping="modal")
    return replace(spec, weights_kip=w, heights_in=h, storey_k_kip_in=k, xi=xi)


def misdeclare(spec: Specimen, frequency: float = 0.0, damping: float = 1.0,
               weight: float = 0.0) -> Specimen:
    """A declaration off by exactly the given amounts (not random): every fixed-base
    frequency x (1 + frequency) (stiffnesses x (1 + frequency)² and x the weight change),
    every damping ratio x damping, every weight x (1 + weight)."""
    if spec.kind == "none":
        return spec
    w = tuple(x * (1 + weight) for x in spec.weights_kip)
    if spec.kind == "rigid":
        return replace(spec, weights_kip=w)
    k = tuple(kk * (1 + weight) * (1 + frequency) ** 2 for kk in spec.storey_k_kip_in)
    mode_xi = (tuple(float(x * damping) for x in spec.modal_damping())
               if spec.mode_xi or spec.is_rayleigh else ())
    return replace(spec, weights_kip=w, storey_k_kip_in=k, xi=spec.xi * damping,
                   mode_xi=mode_xi, rayleigh=None, damping="modal" if mode_xi else spec.damping)
