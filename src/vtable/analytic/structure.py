"""Shear-building matrices (eq 4.5): mass, stiffness, modal damping, fixed-base modes;
the fixed-base frequencies any specimen declares or implies."""

from __future__ import annotations

import functools

import numpy as np
import scipy.linalg
import scipy.optimize

from vtable.errors import VtableError
from vtable.params.specimen import SDOFSpecimen, ShearBuilding, Specimen

TWO_PI = 2 * np.pi


def stiffness_matrix(k: np.ndarray) -> np.ndarray:
    """Tridiagonal K of a shear building from storey stiffnesses k_1 (ground) .. k_n."""
    k = np.asarray(k, dtype=float)
    n = len(k)
    K = np.diag(k + np.append(k[1:], 0.0))
    idx = np.arange(n - 1)
    K[idx, idx + 1] = K[idx + 1, idx] = -k[1:]
    return K


def fixed_base_modes(M: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Circular frequencies (ascending) and mass-normalised mode shapes (columns); NaN for
    a mode of negative stiffness (a fit trying storeys that cannot stand: callers refuse
    non-finite frequencies)."""
    w2, phi = scipy.linalg.eigh(K, M)
    with np.errstate(invalid="ignore"):
        return np.sqrt(w2), phi


#: the relative frequency error below which a building's storeys reproduce its modes (a
#: fitted model's frequencies land anywhere: 1e-8 refused a fit's end point at 2e-8)
MATCHED = 1e-6


def storey_stiffnesses(masses: np.ndarray, frequencies_hz: np.ndarray) -> np.ndarray:
    """Storey stiffnesses whose fixed-base frequencies are `frequencies_hz`.

    The inverse eigenvalue problem is solved by least squares on log k, from equal storeys
    and, if that start ends short, from storeys as stiff as the mass they carry; frequencies
    that no shear building with these masses can have (every mode matched to `MATCHED`) are
    an error.
    """
    m = np.asarray(masses, dtype=float)
    target = TWO_PI * np.sort(np.asarray(frequencies_hz, dtype=float))
    M = np.diag(m)
    scale = (target[0] ** 2) * m.sum() * len(m)
    above = np.cumsum(m[::-1])[::-1]

    def resid(logk: np.ndarray) -> np.ndarray:
        w, _ = fixed_base_modes(M, stiffness_matrix(np.exp(logk)))
        return w / target - 1.0

    best = None
    for k0 in (scale * np.ones(len(m)), scale * above / above.mean()):
        sol = scipy.optimize.least_squares(resid, np.log(k0), xtol=1e-14, ftol=1e-14,
                                           gtol=1e-14)
        if best is None or np.max(np.abs(sol.fun)) < np.max(np.abs(best.fun)):
            best = sol
        if np.max(np.abs(best.fun)) <= MATCHED:
            return np.exp(best.x)
    raise VtableError("ShearBuilding.frequencies_hz: no shear building with these masses has "
                      f"these frequencies (mismatch {np.max(np.abs(best.fun)):.2g})")


def building_stiffnesses(b: ShearBuilding) -> np.ndarray:
    """Storey stiffnesses k_1 .. k_n: given, or from the fixed-base frequencies (solved once
    per masses and frequencies: the bodies and the damping matrix both need them)."""
    if b.stiffnesses is not None:
        return np.asarray(b.stiffnesses, dtype=float)
    return np.array(_storey_stiffnesses_cached(tuple(map(float, b.masses)),
                                               tuple(map(float, b.frequencies))))


def storey_stiffnesses_of(spec: Specimen) -> list[float]:
    """Each storey's elastic stiffness (N/m) from the bottom: a SDOF frame's k_s (eq 3.8),
    a shear building's k_1 .. k_n; none for a bare table or a block."""
    if isinstance(spec, SDOFSpecimen):
        return [spec.stiffness]
    if isinstance(spec, ShearBuilding):
        return [float(k) for k in building_stiffnesses(spec)]
    return []


def storey_masses(spec: Specimen) -> list[float]:
    """The mass each storey's drift coordinate carries (kg), from the bottom: a SDOF
    frame's m_s, a building's floor masses; none for a bare table or a block."""
    if isinstance(spec, SDOFSpecimen):
        return [spec.mass]
    if isinstance(spec, ShearBuilding):
        return [float(m) for m in spec.masses]
    return []


def storey_channels(drifts: list[np.ndarray], floor_acc: list[np.ndarray],
                    masses: list[float]) -> dict[str, np.ndarray]:
    """The run format's storey channels (SI) from each storey's drift (floor K minus floor
    K−1, the platen floor 0) and each floor's absolute acceleration: floorK_drift, and
    floorK_shear = −Σ_{j≥K} m_j a_j, the inertial forces of the floors above storey K (how
    a lab computes it from its floor accelerometers and the masses; + resists + drift)."""
    out: dict[str, np.ndarray] = {}
    above = np.zeros_like(floor_acc[0])
    for k in range(len(drifts), 0, -1):
        above = above - masses[k - 1] * floor_acc[k - 1]
        out[f"floor{k}_drift"] = drifts[k - 1]
        out[f"floor{k}_shear"] = above
    return out


@functools.lru_cache(maxsize=64)
def _storey_stiffnesses_cached(masses: tuple[float, ...],
                               frequencies_hz: tuple[float, ...]) -> tuple[float, ...]:
    return tuple(storey_stiffnesses(np.array(masses), np.array(frequencies_hz)))


def building_matrices(b: ShearBuilding) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """M, K and the classical damping matrix C = M Φ diag(2 ξ_i ω_i) Φᵀ M, each fixed-base
    mode i at its own ratio ξ_i (`ShearBuilding.damping_ratios`: one ratio, one per mode, or
    Rayleigh's, for which C = α M + β K exactly), in the storeys' displacements relative to
    the base (`tables.bodies.specimen_damping` gives C on the storey drifts the multibody
    chain uses)."""
    M = np.diag(b.masses)
    K = stiffness_matrix(building_stiffnesses(b))
    w, phi = fixed_base_modes(M, K)
    C = M @ phi @ np.diag(2 * b.damping_ratios(w) * w) @ phi.T @ M
    return M, K, C


def modal_damping(b: ShearBuilding) -> np.ndarray:
    """The damping ratio of each fixed-base mode of `b`, lowest mode first (the modes are
    computed only for Rayleigh damping, whose ratios depend on them)."""
    if b.rayleigh is None:
        return b.damping_ratios(np.ones(b.n))
    M = np.diag(b.masses)
    w, _ = fixed_base_modes(M, stiffness_matrix(building_stiffnesses(b)))
    return b.damping_ratios(w)


def specimen_frequencies(spec: Specimen) -> list[float]:
    """The fixed-base natural frequencies (Hz) a specimen declares or implies (a shear
    building given by stiffnesses: its eq 4.5 modes); none for a bare table or a block."""
    if isinstance(spec, SDOFSpecimen):
        return [spec.frequency]
    if isinstance(spec, ShearBuilding):
        if spec.frequencies is not None:
            return list(spec.frequencies)
        M, K, _ = building_matrices(spec)
        w, _ = fixed_base_modes(M, K)
        return [float(x) for x in w / TWO_PI]
    return []
