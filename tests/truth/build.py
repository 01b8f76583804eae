"""Turn a Table and a Specimen into the numeric model (parameter vector, flags, matrices)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import constants as c
from . import model as m
from .errors import TruthError
from .specimens import Specimen
from .tables import Table

PISTON_MASS_FRACTION = 0.02  # backlash: piston + rod mass as a fraction of the platen mass
CONNECTION_HZ = 150.0  # backlash: piston-on-connection frequency when engaged
CONNECTION_XI = 0.2
BOUC_WEN_N = 8.0  # yielding_storey: sharpness of the elastic-plastic transition
FRICTION_V_EPS = 0.005 * c.INCH  # m/s: tanh smoothing of sign(ẋ) in the Coulomb friction


@dataclass
class Built:
    table: Table
    specimen: Specimen
    p: np.ndarray
    fl: np.ndarray
    Ms: np.ndarray
    Ks: np.ndarray
    Cs: np.ndarray
    hs: np.ndarray
    c2s: np.ndarray
    hy: np.ndarray  # Bouc–Wen storeys: (n, N_HY), see model.H_*
    delay: float  # s
    pitch_actuator: dict  # two_directional: ω_r, ξ_r, k_r and the passive k_p, c_p

    @property
    def n_state(self) -> int:
        """Base states, the floors (x_i, v_i) and, with Bouc–Wen storeys, one z per storey
        (z_j at N_BASE + 2n + j; a storey that does not yield leaves its z at rest)."""
        n = int(self.fl[m.F_N])
        return m.N_BASE + (3 if self.fl[m.F_HYST] else 2) * n

    def active_states(self) -> list[int]:
        """States that carry dynamics in this configuration (for linearisation)."""
        fl = self.fl
        act = [m.S_X, m.S_V, m.S_PL]
        if fl[m.F_PITCH]:
            act += [m.S_TH, m.S_OM]
        if fl[m.F_PITCH] == 2:
            act.append(m.S_MR)
        if fl[m.F_FFILT]:
            act.append(m.S_PF)
        if fl[m.F_LAG]:
            act.append(m.S_Q)
        if fl[m.F_BACK]:
            act += [m.S_XP, m.S_VP]
        if fl[m.F_FOUND]:
            act += [m.S_XF, m.S_VF]
        if fl[m.F_CTRL] and self.p[m.P_PIDI] != 0:
            act.append(m.S_INT)
        if fl[m.F_RES]:
            act += [m.S_XR, m.S_VR]
        if fl[m.F_DFILT]:
            act.append(m.S_DF)
        if fl[m.F_REFG]:
            act += [m.S_XG, m.S_VG]
        if fl[m.F_NOTCH1]:
            act += [m.S_N1A, m.S_N1B]
        if fl[m.F_NOTCH2]:
            act += [m.S_N2A, m.S_N2B]
        if fl[m.F_YIELD]:
            act.append(m.S_Z)
        act += list(range(m.N_BASE, m.N_BASE + 2 * int(fl[m.F_N])))
        if fl[m.F_HYST]:
            # z of each yielding storey (linearised at rest the storey is elastic, k; z − d/u_y
            # is conserved, a root at 0)
            act += [m.N_BASE + 2 * int(fl[m.F_N]) + j for j in range(int(fl[m.F_N]))
                    if self.hy[j, m.H_ON]]
        return sorted(act)


def pitch_actuator_split(k_theta: float, c_theta: float, inertia: float,
                         f_r: float = c.S862_F_R) -> dict:
    """Split a total rocking impedance (k_θ, c_θ at the coupled frequency, eqs 8.31-8.33)
    into the vertical actuators' servo loop (eq 8.2) and the passive stabilizers (eq 8.6).

    §8.6.2: at 2.58 Hz the actuators contribute k_v = 7.72e9 lb-in/rad and c_v = 1.04e8
    lb-in-s/rad, and f_r = 21 Hz is assumed. Eqs 8.28-8.29 with a = 2ξ_r ω_r and
    D = ω² + a² give c_v D = Iω_r²(a - k_r) and k_v D = Iω_r²(ω² + a k_r); eliminating k_r,
    k_v = Iω_r² - a c_v, so a = (Iω_r² - k_v)/c_v and k_r = a - c_v D/(Iω_r²).
    The stabilizers take the rest: k_p = k_θ - k_v, c_p = c_θ - c_v (eqs 8.32-8.33).
    """
    w = 2 * math.pi * c.T81_COUPLED_HZ
    wr = 2 * math.pi * f_r
    kv, cv = c.S862_K_V, c.S862_C_V
    a = (inertia * wr**2 - kv) / cv
    if a <= 0:
        raise TruthError("two_directional: f_r too low for the §8.6.2 k_v (negative ξ_r)")
    kr = a - cv * (w**2 + a**2) / (inertia * wr**2)
    kp, cp = k_theta - kv, c_theta - cv
    if kp <= 0 or cp <= 0:
        raise TruthError(f"two_directional: k_theta, c_theta ({k_theta / c.LB_IN:.3g}, "
                         f"{c_theta / c.LB_IN:.3g}) must exceed the vertical actuators' share "
                         "(7.72e9 lb-in/rad, 1.04e8 lb-in-s/rad)")
    return {"w_r": wr, "xi_r": a / (2 * wr), "k_r": kr, "k_p": kp, "c_p": cp}


def build(table: Table, spec: Specimen, dt: float) -> Built:
    p = np.zeros(m.N_PARAM)
    fl = np.zeros(m.N_FLAG, dtype=np.int64)
    eff = table.effects
    p[m.P_MT] = table.platen_mass
    p[m.P_MTE] = table.platen_mass * table.com_height
    p[m.P_I] = table.pitch_inertia
    p[m.P_A] = table.area
    p[m.P_V] = table.volume
    p[m.P_BETA] = table.beta
    p[m.P_KCT] = table.leakage
    p[m.P_KT] = table.k_t
    p[m.P_KP] = table.k_p
    p[m.P_PS] = table.supply_pressure
    p[m.P_CPLAT] = table.platen_damping
    fl[m.F_PITCH] = {"none": 0, "hybrid": 1, "two_directional": 2}[table.pitch]
    pitch_act: dict = {}
    if table.pitch == "hybrid":
        p[m.P_KTH], p[m.P_CTH] = table.k_theta, table.c_theta
    elif table.pitch == "two_directional":
        pitch_act = pitch_actuator_split(table.k_theta, table.c_theta, table.pitch_inertia)
        p[m.P_IR] = table.pitch_inertia
        p[m.P_WR], p[m.P_XIR], p[m.P_KR] = pitch_act["w_r"], pitch_act["xi_r"], pitch_act["k_r"]
        p[m.P_KPAS], p[m.P_CPAS] = pitch_act["k_p"], pitch_act["c_p"]
    law = table.law
    if law is not None:
        fl[m.F_CTRL] = 1
        p[m.P_KQ], p[m.P_KD] = table.valve_gain, law.displacement_gain
        p[m.P_PIDP], p[m.P_PIDI], p[m.P_PIDD] = law.p, law.i, law.d
        p[m.P_TV], p[m.P_TA] = law.feedforward_velocity, law.feedforward_acceleration
        p[m.P_KVF], p[m.P_KAF] = law.velocity_gain, law.acceleration_gain
        p[m.P_KDP] = law.pressure_gain
        if law.derivative_filter > 0:
            fl[m.F_DFILT] = 1
            p[m.P_TDF] = law.derivative_filter
        if law.reference is not None:
            fl[m.F_REFG] = 1
            p[m.P_WG], p[m.P_ZG] = 2 * math.pi * law.reference[0], law.reference[1]
        for k, nt in enumerate(law.notches):
            zz, zp = nt.zetas
            fl[m.F_NOTCH1 + k] = 1 if nt.on == "error" else 2
            base = (m.P_N1W, m.P_N2W)[k]
            p[base], p[base + 1], p[base + 2] = 2 * math.pi * nt.frequency_hz, zz, zp
    if table.force_measured == "load_cell":
        fl[m.F_LOADCELL] = 1
    # --- effects ------------------------------------------------------------------------
    if "force_feedback_filter" in eff:
        fl[m.F_FFILT] = 1
        p[m.P_RC] = eff["force_feedback_filter"]["rc"]
    if "valve_flow_nonlinearity" in eff:
        fl[m.F_ORIFICE] = 1
    if "pump_pressure_drop" in eff:
        fl[m.F_PUMP] = 1
        p[m.P_PUMP] = eff["pump_pressure_drop"]["drop_psi_per_gpm"] * c.PSI / c.GPM
    if "actuator_friction" in eff:
        fl[m.F_FRIC] = 1
        p[m.P_FRIC] = eff["actuator_friction"]["friction"] * c.KIP
        p[m.P_VEPS] = FRICTION_V_EPS
    if "flow_saturation" in eff:
        fl[m.F_SAT] = 1
        p[m.P_VMAX] = eff["flow_saturation"]["v_max"] * c.INCH
    tau, delay = table.valve_tau, 0.0
    if "valve_dynamics" in eff:
        tau, delay = eff["valve_dynamics"]["tau"], eff["valve_dynamics"]["delay"]
    if tau > 0:
        fl[m.F_LAG] = 1
        p[m.P_TAU] = tau
    if delay > 0:
        if delay < dt:
            raise TruthError(f"valve_dynamics.delay = {delay:g} s is shorter than the internal "
                             f"step {dt:g} s; use 0 or at least one step")
        fl[m.F_DELAY] = 1
        p[m.P_DELAY] = delay
    if "oil_column_air" in eff:
        fl[m.F_AIR] = 1
        p[m.P_AIR] = eff["oil_column_air"]["air_ratio"]
    if "foundation_compliance" in eff:
        fl[m.F_FOUND] = 1
        mf = table.foundation_mass
        wf = 2 * math.pi * eff["foundation_compliance"]["f_f"]
        p[m.P_MF], p[m.P_KF] = mf, mf * wf**2
        p[m.P_CF] = 2 * eff["foundation_compliance"]["xi_f"] * mf * wf
    if "platen_resonator" in eff:
        r = eff["platen_resonator"]
        fl[m.F_RES] = 1
        wr = 2 * math.pi * r["f_r"]
        p[m.P_MRES], p[m.P_KRES] = r["m_r"], r["m_r"] * wr**2
        p[m.P_CRES] = 2 * r["xi_r"] * r["m_r"] * wr
    if "backlash" in eff:
        fl[m.F_BACK] = 1
        mp = PISTON_MASS_FRACTION * table.platen_mass
        wc = 2 * math.pi * CONNECTION_HZ
        p[m.P_MP], p[m.P_KC], p[m.P_CC] = mp, mp * wc**2, 2 * CONNECTION_XI * mp * wc
        p[m.P_GAP] = eff["backlash"]["gap_in"] * c.INCH
    # --- specimen -------------------------------------------------------------------------
    n = spec.n
    fl[m.F_N] = n
    if spec.kind == "rigid":
        mb = spec.masses()[0]
        hb = spec.heights()[0]
        p[m.P_MB], p[m.P_MBH] = mb, mb * hb
        p[m.P_IB] = spec.inertia_kip_in_s2 * c.KIP_IN_S2 + mb * hb**2
    if n:
        Ms, Ks, Cs, hs = spec.masses(), spec.stiffness(), spec.damping_matrix(), spec.heights()
    else:
        Ms, Ks, Cs, hs = np.ones(1), np.zeros((1, 1)), np.zeros((1, 1)), np.zeros(1)
    c2s = np.zeros(max(n, 1))
    if "amplitude_dependent_damping" in eff:
        if n == 0:
            raise TruthError("amplitude_dependent_damping needs a sdof or shear_building "
                             "specimen")
        fl[m.F_ADD] = 1
        gamma = eff["amplitude_dependent_damping"]["gamma"] / c.INCH  # 1/m
        for j in range(n):
            # c₂ = 3π m γ/4 with m the mass the storey carries (all floors above it):
            # equivalent ξ = 4 c₂ X/(3π m) = γ X for a drift amplitude X
            c2s[j] = 3 * math.pi * Ms[j:].sum() * gamma / 4
    if "specimen_degradation" in eff:
        if n == 0:
            raise TruthError("specimen_degradation needs a sdof or shear_building specimen")
        fl[m.F_DEGR] = 1
        p[m.P_DLOSS] = eff["specimen_degradation"]["stiffness_loss"]
        p[m.P_DE0] = eff["specimen_degradation"]["energy_kip_in"] * c.KIP * c.INCH  # J
    hy = np.zeros((max(n, 1), m.N_HY))
    h = spec.hysteresis
    if h is not None:
        if n == 0:
            raise TruthError("hysteresis needs a sdof or shear_building specimen")
        fl[m.F_HYST] = 1
        for K, uy, alpha in zip(h.storeys, h.yield_drift_in, h.post_yield_ratio, strict=True):
            j = K - 1
            hy[j, m.H_ON] = 1.0
            hy[j, m.H_K] = spec.storey_k_kip_in[j] * c.KIP / c.INCH  # as in spec.stiffness()
            hy[j, m.H_UY] = uy * c.INCH
            hy[j, m.H_ALPHA] = alpha
            hy[j, m.H_N], hy[j, m.H_BETA], hy[j, m.H_GAMMA] = h.n, h.beta, h.gamma
    if "yielding_storey" in eff:
        if n == 0:
            raise TruthError("yielding_storey needs a sdof or shear_building specimen")
        if h is not None and 1 in h.storeys:
            raise TruthError("yielding_storey: storey 1 already yields by the specimen's "
                             "hysteresis; use one or the other")
        fl[m.F_YIELD] = 1
        k1 = spec.storey_k_kip_in[0] * c.KIP / c.INCH
        fy = eff["yielding_storey"]["yield_fraction"] * spec.total_weight_kip * c.KIP
        p[m.P_K1], p[m.P_DY] = k1, fy / k1
        p[m.P_ALPHA] = eff["yielding_storey"]["post_yield_ratio"]
        p[m.P_BWN] = BOUC_WEN_N
    return Built(table, spec, p, fl, np.ascontiguousarray(Ms, dtype=float),
                 np.ascontiguousarray(Ks, dtype=float), np.ascontiguousarray(Cs, dtype=float),
                 np.ascontiguousarray(hs, dtype=float), c2s, hy, delay, pitch_act)
