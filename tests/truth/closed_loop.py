"""x_t/x_c of a rigid platen on one lumped actuator under any of the truth's controllers,
derived by hand (the reference the truth's linearisation and vtable's controller kinds are
checked against), and the tables' constants it takes."""

from __future__ import annotations

from truth import constants as const


def closed_loop(s, *, m, c, A, V, beta, kl, Kq, tau_v, kd, p=1.0, i=0.0, d=0.0, tau_f=0.0,
                Tv=0.0, Ta=0.0, kv=0.0, ka=0.0, kdp=0.0, Ne=1.0, Nd=1.0, R=1.0):
    """x_t/x_c of a rigid platen m (damping c) on one lumped actuator, derived by hand:
    m s² X + c s X = A P;  (V/4β) s P + k_l P + A s X = Q;  Q = K_q N_d V/(τ_v s + 1);
    V = k_d C N_e (R X_c - X) + k_d (T_v s + T_a s²) R X_c - (k_v s + k_a s²) X - k_dp P,
    C = p + i/s + d s/(τ_f s + 1). With Z = (m s² + c s)/A (P = Z X):
    H = G k_d (C N_e + F) R / [(V s/4β + k_l) Z + A s + G (k_d C N_e + k_v s + k_a s²
    + k_dp Z)],  G = K_q N_d/(τ_v s + 1), F = T_v s + T_a s²."""
    Z = (m * s**2 + c * s) / A
    G = Kq * Nd / (tau_v * s + 1)
    C = (p + i / s + d * s / (tau_f * s + 1)) * Ne
    Fw = Tv * s + Ta * s**2
    den = (V * s / (4 * beta) + kl) * Z + A * s + G * (kd * C + kv * s + ka * s**2 + kdp * Z)
    return G * kd * (C + Fw) * R / den


def lnec_constants():
    L = const.LNEC
    return dict(m=L["platen_mass"], c=L["damping"], A=L["area"], V=L["volume"], beta=L["beta"],
                kl=L["leakage"], Kq=L["valve_gain"], tau_v=L["valve_tau"], kd=L["disp_gain"])


def eerc_constants():
    n = 3
    return dict(m=100e3 * const.LBF / const.G, c=0.0, A=n * 25.4 * const.INCH**2,
                V=n * 317.5 * const.INCH**3, beta=94000.0 * const.PSI,
                kl=n * 0.0787 * const.INCH**3 / const.PSI,
                Kq=n * 663.0 * const.INCH**2 / (2.0 / const.INCH), tau_v=0.0,
                kd=2.0 / const.INCH)
