"""The report's closed-form relations, each citing its equation. SI in, SI out."""

from __future__ import annotations

import math

import numpy as np

from vtable.errors import VtableError
from vtable.params.loops import OpenLoop, spring_frequency

TWO_PI = 2 * math.pi


# ---- servo loop (ch. 6) -----------------------------------------------------------------
def h_at_open_loop_frequency(ol: OpenLoop) -> float:
    """H(iω_o) = k_o/(k_o - 2ξ_o ω_o), real and negative for a stable loop (eq 6.19)."""
    return ol.k_o / (ol.k_o - 2 * ol.xi_o * ol.omega_o)


def gain_margin_bare(ol: OpenLoop) -> float:
    """G_m = 2ξ_o ω_o / k_o (eq 6.20); > 1 is the stability condition 6.17b."""
    return 2 * ol.xi_o * ol.omega_o / ol.k_o


# ---- effective mass (ch. 7) -------------------------------------------------------------
def transmissibility(f_hz, f_s: float, xi_s: float) -> np.ndarray:
    """x_s^t/x_t = (2ξ_sω_s s + ω_s²)/(s² + 2ξ_sω_s s + ω_s²) at s = j2πf (eq 7.8)."""
    s = 1j * TWO_PI * np.asarray(f_hz, dtype=float)
    ws = TWO_PI * f_s
    return (2 * xi_s * ws * s + ws**2) / (s**2 + 2 * xi_s * ws * s + ws**2)


def effective_mass(f_hz, m_t: float, m_s: float, f_s: float, xi_s: float) -> np.ndarray:
    """m_e = m_t (1 + (m_s/m_t) x_s^t/x_t), complex (eq 7.16)."""
    return m_t + m_s * transmissibility(f_hz, f_s, xi_s)


def effective_mass_limits(m_t: float, m_s: float, xi_s: float) -> dict[str, float]:
    """Magnitudes of m_e: low frequency (7.17), high (7.18), just below (7.19) and just
    above (7.20) the structure's frequency."""
    return {"low": m_t + m_s, "high": m_t, "below": m_t + m_s / (2 * xi_s),
            "above": m_t - m_s / (2 * xi_s)}


# ---- effective heights (§4.2.2) ---------------------------------------------------------
def effective_height_least_squares(M: np.ndarray, r_theta: np.ndarray) -> float:
    """h_e = r_tᵀ M² r_θ / r_tᵀ M² r_t (eq 4.15); with diagonal M it is eq 4.16."""
    M = np.atleast_2d(np.asarray(M, dtype=float))
    r_t = np.ones(M.shape[0])
    M2 = M @ M
    return float(r_t @ M2 @ r_theta / (r_t @ M2 @ r_t))


def effective_height_mode(M: np.ndarray, phi1: np.ndarray, r_theta: np.ndarray) -> float:
    """h_e1 = φ₁ᵀ M r_θ / φ₁ᵀ M r_t (eq 4.22)."""
    M = np.atleast_2d(np.asarray(M, dtype=float))
    return float(phi1 @ M @ r_theta / (phi1 @ M @ np.ones(M.shape[0])))


def effective_height_first_mode(masses, heights) -> float:
    """h_e1 ≈ Σ m_j h_j² / Σ m_j h_j, i.e. eq 4.22 with φ₁ ≈ r_θ (eqs 4.23-4.24)."""
    m, h = np.asarray(masses, dtype=float), np.asarray(heights, dtype=float)
    return float(m @ h**2 / (m @ h))


def modal_mass(masses, heights) -> float:
    """m_1 = φ₁ᵀ M φ₁ with φ₁ = h normalised to 1 at the top (eqs 5.6-5.7)."""
    h = np.asarray(heights, dtype=float)
    phi = h / h[-1]
    return float(np.asarray(masses, dtype=float) @ phi**2)


# ---- springs from frequencies (§5.3.2) --------------------------------------------------
def rocking_coupled_frequency(f_f: float, m_s: float, h: float, k_r: float) -> float:
    """f_r with ω_r² = ω_f²/(1 + m_s ω_f² h²/k_r) (eq 5.4), massless rigid table."""
    wf = TWO_PI * f_f
    return math.sqrt(wf**2 / (1 + m_s * wf**2 * h**2 / k_r)) / TWO_PI


def coupled_frequency(f_f: float, m_s: float, h: float, k_h: float, k_r: float) -> float:
    """f_hr with ω_hr² = ω_f²/(1 + m_s ω_f²/k_h + m_s ω_f² h²/k_r) (eq 5.5)."""
    wf = TWO_PI * f_f
    return math.sqrt(wf**2 / (1 + m_s * wf**2 / k_h + m_s * wf**2 * h**2 / k_r)) / TWO_PI


def rocking_stiffness_from_frequencies(f_f: float, f_r: float, m_s: float, h: float) -> float:
    """k_r from fixed-base and rocking-coupled frequencies, eq 5.4 solved for k_r."""
    if not f_r < f_f:
        raise VtableError(f"rocking-coupled frequency {f_r:g} Hz must be below the "
                          f"fixed-base {f_f:g} Hz")
    wf = TWO_PI * f_f
    return m_s * wf**2 * h**2 / ((f_f / f_r) ** 2 - 1)


def horizontal_stiffness_from_frequencies(f_f: float, f_hr: float, m_s: float, h: float,
                                          k_r: float) -> float:
    """k_h from eq 5.5 given k_r (e.g. from eq 5.4)."""
    wf = TWO_PI * f_f
    rest = (f_f / f_hr) ** 2 - 1 - m_s * wf**2 * h**2 / k_r
    if not rest > 0:
        raise VtableError(f"coupled frequency {f_hr:g} Hz is not below the rocking-coupled "
                          "one: no positive horizontal stiffness fits eq 5.5")
    return m_s * wf**2 / rest


def rocking_stiffness_from_actuators(k_v, d_v, k_p, d_p) -> float:
    """k_r = Σ (k_vi d_vi² + k_pi d_pi²) (eq 5.14)."""
    return float(np.sum(np.asarray(k_v) * np.asarray(d_v) ** 2)
                 + np.sum(np.asarray(k_p) * np.asarray(d_p) ** 2))


# ---- a servo loop with zero command as a frequency-dependent spring (§5.6, §8.5) ------
def feedback_spring(inertia: float, ol: OpenLoop, f_hz) -> tuple[np.ndarray, np.ndarray]:
    """k(ω) and c(ω) of a servo loop holding a zero command.

    k(ω) = J ω_o²(ω² + 2ξ_oω_o k_o)/(ω² + 4ξ_o²ω_o²), c(ω) = J ω_o²(2ξ_oω_o - k_o)/(...)
    with J = m_t for the horizontal actuator (eqs 5.15-5.16) and J = I for the pitch
    actuator (eqs 8.28-8.29).
    """
    w = TWO_PI * np.asarray(f_hz, dtype=float)
    wo, xi, k = ol.omega_o, ol.xi_o, ol.k_o
    den = w**2 + 4 * xi**2 * wo**2
    return (inertia * wo**2 * (w**2 + 2 * xi * wo * k) / den,
            inertia * wo**2 * (2 * xi * wo - k) / den)


def pitch_loop_from_springs(k_v: float, c_v: float, f_hz: float, f_r: float,
                            inertia: float) -> OpenLoop:
    """The pitch loop (f_r, ξ_r, k_r) that gives springs k_v, c_v at f_hz (§8.6.2).

    Eliminating k_r from eqs 8.28-8.29 gives k_v = Iω_r² - 2ξ_rω_r c_v, so
    ξ_r = (Iω_r² - k_v)/(2ω_r c_v) and k_r = 2ξ_rω_r - c_v(ω² + 4ξ_r²ω_r²)/(Iω_r²).
    ξ_r < 0 (f_r below √(k_v/I)/2π) is an unstable pitch loop.
    """
    wr, w = TWO_PI * f_r, TWO_PI * f_hz
    xi = (inertia * wr**2 - k_v) / (2 * wr * c_v)
    if xi <= 0:
        f_min = math.sqrt(k_v / inertia) / TWO_PI
        raise VtableError(f"pitch-loop frequency {f_r:g} Hz gives negative damping: it must "
                          f"exceed {f_min:.2f} Hz for these springs")
    k = 2 * xi * wr - c_v * (w**2 + 4 * xi**2 * wr**2) / (inertia * wr**2)
    return OpenLoop(f_o=f_r, xi_o=xi, k_o=k, source="eqs 8.28-8.29 inverted")


# ---- passive stabilizers (§8.3) and combined rocking (§8.6.1) ---------------------------
def stabilizer_compliance(*, area: float, cylinder_length: float, line_length: float,
                          line_area: float, beta_e: float, line_radius: float = 0.0,
                          line_wall: float = math.inf, line_modulus: float = math.inf,
                          cylinder_radius: float = 0.0, cylinder_wall: float = math.inf,
                          cylinder_modulus: float = math.inf, leakage: float = 0.0) -> float:
    """Δx/F of one stabilizer piston (eq 8.3): oil compression with V = A L_c + a L, hoop
    expansion of the oil line and of the cylinder, and leakage."""
    V = area * cylinder_length + line_area * line_length
    A2 = area**2
    return (V / (2 * beta_e * A2)
            + math.pi * line_radius**3 * line_length / (A2 * line_wall * line_modulus)
            + math.pi * cylinder_radius**3 * cylinder_length
            / (A2 * cylinder_wall * cylinder_modulus)
            + leakage / A2)


def stabilizer_rocking_stiffness(compliance: float, d_p: float) -> float:
    """k_p = (F/Δx) d_p² for the two cross-connected pairs, d_p apart (eq 8.4)."""
    return d_p**2 / compliance


def combined_rocking(k_p: float, c_p: float, inertia: float, pitch_loop: OpenLoop,
                     f_hz: float) -> dict[str, float]:
    """k_θ = k_p + k_v(ω) (8.32), c_θ = c_p + c_v(ω) (8.33), ω_θ² = k_θ/I (8.35),
    ξ_θ = c_θ/(2ω_θ I) (8.36), the pitch loop's springs taken at f_hz."""
    k_v, c_v = feedback_spring(inertia, pitch_loop, f_hz)
    k_t, c_t = k_p + float(k_v), c_p + float(c_v)
    f, xi = spring_frequency(k_t, c_t, inertia)
    return {"k_theta": k_t, "c_theta": c_t, "f_theta": f, "xi_theta": xi}


def stabilizer_rocking(k_theta: float, c_theta: float, inertia: float, pitch_loop: OpenLoop,
                       f_hz: float) -> tuple[float, float]:
    """The passive stabilizers' share k_p = k_θ - k_v(ω), c_p = c_θ - c_v(ω) of a rocking
    spring and dashpot (eqs 8.32-8.33 solved for k_p, c_p; `combined_rocking` is the
    inverse), the vertical actuators' pitch loop taken as a spring at f_hz (eqs 8.28-8.29).

    Raises
    ------
    VtableError
        When the pitch loop alone is stiffer than k_θ, or damps more than c_θ.
    """
    k_v, c_v = feedback_spring(inertia, pitch_loop, f_hz)
    k_p, c_p = k_theta - float(k_v), c_theta - float(c_v)
    if k_p <= 0 or c_p < 0:
        raise VtableError(f"rocking spring {k_theta:.3g} N m/rad, dashpot {c_theta:.3g} "
                          f"N m s/rad: the vertical actuators' pitch loop alone gives "
                          f"{float(k_v):.3g} and {float(c_v):.3g} at {f_hz:g} Hz")
    return k_p, c_p
