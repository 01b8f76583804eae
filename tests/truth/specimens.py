"""Specimens on the platen: none, a rigid block, a SDOF frame (§2.4, Table 8.1) or an
n-storey shear building; and the lab's *declared* version of a specimen (`perturb`).

Heights are measured from the horizontal actuator line (the run format's convention,
29.7 in below the table top). Storey damping is classical: C = M Φ diag(2 ξ_i ω_i) Φᵀ M
with mass-normalised Φ (Chopra, Dynamics of Structures, §11.4: the modal damping matrix),
every fixed-base mode at the ratio `xi` or each at its own (`mode_xi`); or Rayleigh damping
C = α M + β K (Chopra §11.4.1), whose ratio in mode i is ξ_i = α/(2ω_i) + β ω_i/2, with
α, β fixed by two (frequency, ratio) pairs (`rayleigh`), or by ξ at modes 1 and 2 when
`damping="rayleigh"`. A run declares the ratio of every mode (a list).

A sdof or shear building may have yielding (Bouc–Wen) storeys (`Hysteresis`; Wen 1976,
Baber & Wen 1981 with A = 1): storey K of elastic stiffness k and drift u resists with
α k u + (1 − α) k u_y z in place of k u, ż = (u̇ − β|u̇||z|ⁿ⁻¹z − γ u̇|z|ⁿ)/u_y; the viscous
storey damping is unchanged. A run declares it as [specimen.hysteresis].
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
HYSTERESIS_KEYS = ("storeys", "yield_drift_in", "post_yield_ratio", "n", "beta", "gamma")


@dataclass(frozen=True)
class Hysteresis:
    """Bouc–Wen storeys: `storeys` 1-based from the bottom (increasing), one yield drift
    u_y (in) and one post-yield stiffness ratio α per listed storey, and the shape
    parameters n ≥ 1, β, γ shared by all of them."""

    storeys: tuple[int, ...]
    yield_drift_in: tuple[float, ...]
    post_yield_ratio: tuple[float, ...]
    n: float = 2.0
    beta: float = 0.5
    gamma: float = 0.5

    @property
    def z_max(self) -> float:
        """The bound of |z| reached under monotonic drift: (1/(β + γ))^(1/n)."""
        return (1.0 / (self.beta + self.gamma)) ** (1.0 / self.n)

    def declared(self) -> dict:
        """The run format's [specimen.hysteresis] table."""
        return {"storeys": list(self.storeys), "yield_drift_in": list(self.yield_drift_in),
                "post_yield_ratio": list(self.post_yield_ratio), "n": self.n,
                "beta": self.beta, "gamma": self.gamma}


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
    hysteresis: Hysteresis | None = None  # yielding storeys (sdof, shear_building)

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
            out = {"kind": "sdof", "weight_kip": self.weights_kip[0],
                   "height_in": self.heights_in[0],
                   "frequency_hz": self.frequencies_hz()[0], "damping": self.xi}
        else:
            damping = (self.xi if not (self.mode_xi or self.is_rayleigh)
                       else [float(x) for x in self.modal_damping()])
            out = {"kind": "shear_building", "weights_kip": list(self.weights_kip),
                   "heights_in": list(self.heights_in),
                   "frequencies_hz": self.frequencies_hz(), "damping": damping}
        if self.hysteresis is not None:
            out["hysteresis"] = self.hysteresis.declared()
        return out


def _positive(name: str, v: float) -> float:
    if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
        raise TruthError(f"specimen: {name} must be a positive number, got {v!r}")
    return float(v)


def _number(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _hysteresis(h, n: int) -> Hysteresis | None:
    """Check a hysteresis dict (or a Hysteresis) for a specimen of n storeys."""
    if h is None:
        return None
    if isinstance(h, Hysteresis):
        h = h.declared()
    if not isinstance(h, dict):
        raise TruthError(f"specimen: hysteresis must be a dict, got {type(h).__name__}")
    unknown = sorted(set(h) - set(HYSTERESIS_KEYS))
    if unknown:
        raise TruthError(f"specimen: hysteresis has unknown key(s) {unknown}; it takes "
                         f"{list(HYSTERESIS_KEYS)}")
    storeys = h.get("storeys", list(range(1, n + 1)))
    if isinstance(storeys, int) and not isinstance(storeys, bool):
        storeys = [storeys]
    if (not isinstance(storeys, list | tuple) or not storeys
            or not all(isinstance(k, int) and not isinstance(k, bool) for k in storeys)
            or not all(1 <= k <= n for k in storeys) or len(set(storeys)) != len(storeys)):
        raise TruthError(f"specimen: hysteresis.storeys must be distinct storey numbers in "
                         f"1..{n}, got {storeys!r}")

    def per_storey(key: str, ok, what: str) -> list[float]:
        if key not in h:
            raise TruthError(f"specimen: hysteresis.{key} is required")
        v = h[key]
        vals = list(v) if isinstance(v, list | tuple) else [v] * len(storeys)
        if len(vals) != len(storeys):
            raise TruthError(f"specimen: hysteresis.{key} needs {len(storeys)} value(s) (one "
                             f"per storey) or one number, got {v!r}")
        if not all(_number(x) and ok(x) for x in vals):
            raise TruthError(f"specimen: hysteresis.{key} must be {what}, got {v!r}")
        return [float(x) for x in vals]

    uy = per_storey("yield_drift_in", lambda x: x > 0, "positive (in)")
    alpha = per_storey("post_yield_ratio", lambda x: 0 <= x <= 1, "in [0, 1]")
    shape = {}
    for key, default in (("n", 2.0), ("beta", 0.5), ("gamma", 0.5)):
        v = h.get(key, default)
        if not _number(v):
            raise TruthError(f"specimen: hysteresis.{key} must be a number, got {v!r}")
        shape[key] = float(v)
    if shape["n"] < 1:
        raise TruthError(f"specimen: hysteresis.n must be >= 1, got {shape['n']!r}")
    if shape["beta"] + shape["gamma"] <= 0:
        raise TruthError("specimen: hysteresis needs beta + gamma > 0 (bounded z), got "
                         f"beta={shape['beta']!r}, gamma={shape['gamma']!r}")
    order = sorted(range(len(storeys)), key=lambda i: storeys[i])
    return Hysteresis(tuple(int(storeys[i]) for i in order), tuple(uy[i] for i in order),
                      tuple(alpha[i] for i in order), **shape)


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


def sdof(weight_kip: float, height_in: float, f_hz: float, xi: float,
         hysteresis: dict | None = None) -> Specimen:
    """A SDOF structure (§2.4, Table 8.1: 68 kips at 219 in, 2.87 Hz, 1 %).

    hysteresis: a yielding storey (its only storey is 1), e.g. {"yield_drift_in": 0.3,
    "post_yield_ratio": 0.05} (n, beta, gamma optional: 2, 0.5, 0.5)."""
    m = _positive("weight_kip", weight_kip) * KIP / G
    k = m * (2 * math.pi * _positive("f_hz", f_hz)) ** 2
    if not 0 <= xi < 1:
        raise TruthError(f"specimen: xi must be in [0, 1), got {xi!r}")
    return Specimen("sdof", (float(weight_kip),), (float(height_in),),
                    (k / (KIP / INCH),), float(xi), hysteresis=_hysteresis(hysteresis, 1))


def building(weights_kip: list[float], heights_in: list[float],
             storey_k_kip_in: list[float] | None = None,
             frequencies_hz: list[float] | None = None, xi: float | list[float] = 0.02,
             damping: str = "modal",
             rayleigh: tuple[tuple[float, float], tuple[float, float]] | None = None,
             hysteresis: dict | None = None) -> Specimen:
    """An n-storey shear building, floors from the bottom. Give the storey stiffnesses
    (kip/in) or the n fixed-base frequencies (the stiffnesses are then solved for, from
    a uniform-stiffness start; an unreachable set of frequencies is an error).

    Damping: `xi` one ratio for every mode or a list (one per mode, from the bottom one);
    `rayleigh` ((f₁ Hz, ξ₁), (f₂ Hz, ξ₂)): C = α M + β K through those two pairs.

    hysteresis: yielding storeys, {"storeys": [2], "yield_drift_in": [0.3],
    "post_yield_ratio": [0.05], "n": 2.0, "beta": 0.5, "gamma": 0.5} (storeys 1-based from
    the bottom, all when left out; one value per listed storey or one for all)."""
    n = len(weights_kip)
    if n == 0 or len(heights_in) != n:
        raise TruthError(f"specimen: weights_kip and heights_in must have the same "
                         f"non-zero length, got {len(weights_kip)} and {len(heights_in)}")
    hyst = _hysteresis(hysteresis, n)
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
                    rayleigh=rayleigh, hysteresis=hyst)
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
            weight: float = 0.05, height: float = 0.0, yield_drift: float = 0.1) -> Specimen:
    """What a lab would declare: each property moved by between half and all of its bound,
    with a random sign (seeded), so the declaration always differs from the truth.

    frequency: relative bound on the fixed-base frequencies (stiffnesses scale with it);
    damping: factor bound (ξ multiplied or divided by up to `damping`);
    weight, height: relative bounds;
    yield_drift: relative bound on each yielding storey's yield drift (post-yield ratio,
    n, β, γ kept); drawn after everything else, and only for a specimen with hysteresis,
    so the other draws of a seed do not depend on it.
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
    hyst = spec.hysteresis
    if hyst is not None:  # the last draws: a seed's other draws are those of an elastic one
        if not 0 <= yield_drift < 1:
            raise TruthError(f"perturb: yield_drift must be in [0, 1), got {yield_drift!r}")
        hyst = replace(hyst, yield_drift_in=tuple(u * (1 + rel(yield_drift))
                                                  for u in hyst.yield_drift_in))
    if mode_xi:
        return replace(spec, weights_kip=w, heights_in=h, storey_k_kip_in=k, xi=mode_xi[0],
                       mode_xi=mode_xi, rayleigh=None, damping="modal", hysteresis=hyst)
    return replace(spec, weights_kip=w, heights_in=h, storey_k_kip_in=k, xi=xi,
                   hysteresis=hyst)


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
