"""The equations of motion, written out directly (SI), and a fixed-step RK4 integrator.

Generalised coordinates: platen x_t (at the horizontal actuator line) and pitch θ
(positive when a point above the table moves +x), optional piston x_p (backlash),
optional reaction mass x_f (foundation compliance), the specimen's floors x_i (absolute).

Platen (Lagrange, c.o.m. at height e, inertia I about the actuator line):
    [m_t + m_b        m_t e + m_b h_b ] [ẍ_t]   [F_x]
    [m_t e + m_b h_b  I + I_b + m_b h_b²] [θ̈ ] = [M_θ]
Specimen (relative coordinates u_i = x_i - x_t - h_i θ, as eqs 7.1-7.2, 8.7-8.9; with
degradation K is scaled by 1 - L(1 - exp(-E/E0)), Ė = u̇ᵀ C u̇):
    m_i ẍ_i = -r_i,  r = K u + C u̇ + (storey nonlinearities),
    F_x += Σ r_i,  M_θ += Σ h_i r_i.
Bouc–Wen storeys (F_HYST; Wen 1976, Baber & Wen 1981, A = 1): storey j's elastic force
k_j d_j (d_j = u_j - u_{j-1}, u_0 = 0) becomes α k_j d_j + (1 - α) k_j u_y z_j, i.e. the
storey force (1 - α) k_j (u_y z_j - d_j) is added to K u, with the state z_j (dimensionless,
after the floors) ż_j = (ḋ_j - β|ḋ_j||z_j|ⁿ⁻¹z_j - γ ḋ_j|z_j|ⁿ)/u_y, stepped by the same RK4.
Actuator (eqs 6.1-6.5, B.4-B.6, lumped): u = k_t[(x_c - x_m) - k_p P_fb], P_fb = P_L or
the RC high-pass of P_L (eq B.4); u -> [delay] -> [spool lag τ] -> [orifice √(P_s - sgn P_L),
eq C.14] -> [rated-flow cap A v_max] -> q; (V/4β_e) Ṗ_L = q - k_ct P_L - A ẋ_m (ẋ_m the
piston velocity relative to the reaction mass); F_h = A P_L; Coulomb friction F_r tanh(ẋ_m/ε)
(eq C.12). LNEC: u = K_q [P e_V + I ∫e_V + D ė_V] + f_ff A ẋ_c with e_V = K_d (x_c - x_m).
Pitch: hybrid M = -k_θ θ - c_θ θ̇ (eq 8.31); two-directional eq 8.2 servo moment M_r plus
passive M_p = -k_p θ - c_p θ̇ (eq 8.6).
"""

from __future__ import annotations

import numpy as np
from numba import njit

# ---- state indices -----------------------------------------------------------------------
(S_X, S_V, S_TH, S_OM, S_PL, S_PF, S_Q, S_XP, S_VP, S_XF, S_VF, S_MR, S_INT, S_Z, S_XR, S_VR,
 S_DF, S_XG, S_VG, S_N1A, S_N1B, S_N2A, S_N2B, S_E) = range(24)
N_BASE = 24  # floors follow: x_i at N_BASE + i, v_i at N_BASE + n + i

# ---- parameter indices -------------------------------------------------------------------
(P_MT, P_MTE, P_I, P_MB, P_MBH, P_IB, P_A, P_V, P_BETA, P_KCT, P_KT, P_KP, P_RC, P_PS,
 P_VMAX, P_TAU, P_DELAY, P_AIR, P_FRIC, P_VEPS, P_KTH, P_CTH, P_IR, P_WR, P_XIR, P_KR,
 P_KPAS, P_CPAS, P_MF, P_KF, P_CF, P_GAP, P_KC, P_CC, P_MP, P_PUMP, P_CPLAT, P_KQ, P_KD,
 P_PIDP, P_PIDI, P_PIDD, P_TV, P_K1, P_DY, P_ALPHA, P_BWN, P_MRES, P_KRES, P_CRES, P_TA,
 P_KVF, P_KAF, P_KDP, P_TDF, P_WG, P_ZG, P_N1W, P_N1ZZ, P_N1ZP, P_N2W, P_N2ZZ,
 P_N2ZP, P_DLOSS, P_DE0) = range(65)
N_PARAM = 65

# ---- flags ---------------------------------------------------------------------------------
# F_CTRL: 0 the analog three-variable loop in flow units (Table B.5), 1 the law in volts
# (controllers.py); F_NOTCH1/2: 0 none, 1 on the error, 2 on the drive; F_HYST: Bouc–Wen
# storeys (then n states z_j follow the floors: z_j at N_BASE + 2n + j)
(F_PITCH, F_CTRL, F_FFILT, F_ORIFICE, F_FRIC, F_SAT, F_LAG, F_DELAY, F_AIR, F_FOUND, F_BACK,
 F_PUMP, F_YIELD, F_ADD, F_RES, F_DFILT, F_REFG, F_NOTCH1, F_NOTCH2, F_LOADCELL,
 F_N, F_HYST, F_DEGR) = range(23)
N_FLAG = 23

# ---- Bouc–Wen storeys: columns of the (n, N_HY) array hy, one row per storey --------------
# H_ON 1 for a yielding storey; H_K its elastic stiffness (N/m, the same k as in Ks);
# H_UY yield drift (m); H_ALPHA post-yield ratio; H_N, H_BETA, H_GAMMA the shape
(H_ON, H_K, H_UY, H_ALPHA, H_N, H_BETA, H_GAMMA) = range(7)
N_HY = 7

# ---- auxiliary outputs of the right-hand side ----------------------------------------------
# A_U: valve command after delay and lag; A_UC: the controller's own output (before them);
# A_ROD: the force the actuator rod transmits to the platen (A·ΔP - friction, or the
# backlash connection force)
(A_FH, A_ACC, A_ALPHA, A_MR, A_MP, A_XM, A_VM, A_AF, A_QCMD, A_U, A_VBASE, A_UC,
 A_ROD) = range(13)
N_AUX = 13


@njit(cache=True)
def notch(s, ds, i0, w, zz, zp, x, xd):
    """One second-order notch N(s) = 1 + 2(ζ_z - ζ_p)ω s/(s² + 2ζ_p ω s + ω²) on input x
    (rate xd), states z1 = s[i0], z2 = s[i0+1] with Z2/X = s/(s² + 2ζ_p ω s + ω²).
    Returns the output and its rate; writes the states' rates."""
    z1 = s[i0]
    z2 = s[i0 + 1]
    dz2 = -w * w * z1 - 2.0 * zp * w * z2 + x
    ds[i0] = z2
    ds[i0 + 1] = dz2
    c = 2.0 * (zz - zp) * w
    return x + c * z2, xd + c * dz2


@njit(cache=True)
def controller(s, xc, vc, ac, ax, p, fl, ds):
    """Valve command u (m³/s of flow it asks for) from the state, the command (x_c, ẋ_c,
    ẍ_c) and the platen acceleration ẍ_t; writes the controller states' rates into ds.

    F_CTRL 0: u = k_t[(x_c - x_m) - k_p P_fb] (eqs 6.1-6.4, Table B.5).
    F_CTRL 1: u = K_q V with V the law of controllers.py (PID with a filtered derivative,
    feedforward, velocity/acceleration/ΔP feedback, reference generator, notches)."""
    xm = s[S_XP] - s[S_XF] if fl[F_BACK] else s[S_X] - s[S_XF]
    vm = s[S_VP] - s[S_VF] if fl[F_BACK] else s[S_V] - s[S_VF]
    pfb = s[S_PF] if fl[F_FFILT] else s[S_PL]
    if fl[F_CTRL] == 0:
        return p[P_KT] * ((xc - xm) - p[P_KP] * pfb)
    xr, vr, ar = xc, vc, ac
    if fl[F_REFG]:  # x_r/x_c = ω_g²/(s² + 2ζ_g ω_g s + ω_g²)
        wg = p[P_WG]
        ar = wg * wg * (xc - s[S_XG]) - 2.0 * p[P_ZG] * wg * s[S_VG]
        xr, vr = s[S_XG], s[S_VG]
        ds[S_XG] = vr
        ds[S_VG] = ar
    e = xr - xm
    ed = vr - vm
    if fl[F_NOTCH1] == 1:
        e, ed = notch(s, ds, S_N1A, p[P_N1W], p[P_N1ZZ], p[P_N1ZP], e, ed)
    if fl[F_NOTCH2] == 1:
        e, ed = notch(s, ds, S_N2A, p[P_N2W], p[P_N2ZZ], p[P_N2ZP], e, ed)
    ds[S_INT] = e
    if fl[F_DFILT]:  # D(s) = s/(τ_f s + 1)
        dterm = (e - s[S_DF]) / p[P_TDF]
        ds[S_DF] = dterm
    else:
        dterm = ed
    kd = p[P_KD]
    v = (kd * (p[P_PIDP] * e + p[P_PIDI] * s[S_INT] + p[P_PIDD] * dterm)
         + kd * (p[P_TV] * vr + p[P_TA] * ar) - p[P_KVF] * vm - p[P_KAF] * ax - p[P_KDP] * pfb)
    if fl[F_NOTCH1] == 2:
        v, _ = notch(s, ds, S_N1A, p[P_N1W], p[P_N1ZZ], p[P_N1ZP], v, 0.0)
    if fl[F_NOTCH2] == 2:
        v, _ = notch(s, ds, S_N2A, p[P_N2W], p[P_N2ZZ], p[P_N2ZP], v, 0.0)
    return p[P_KQ] * v


@njit(cache=True)
def rhs(t, s, xc, vc, ac, udel, p, fl, Ms, Ks, Cs, hs, c2s, hy, ds, aux):
    """ds = ṡ. `udel` is the delayed valve command (used when F_DELAY is set). The
    mechanics come first (they depend on the state only), then the controller (which may
    feed back the platen acceleration), the valve and the oil column."""
    n = fl[F_N]
    for i in range(ds.shape[0]):
        ds[i] = 0.0
    A = p[P_A]
    # --- kinematics at the actuator --------------------------------------------------------
    vf = s[S_VF] if fl[F_FOUND] else 0.0
    vpist = s[S_VP] if fl[F_BACK] else s[S_V]
    vrel = vpist - vf
    pl = s[S_PL]
    fh = A * pl
    ffr = 0.0
    if fl[F_FRIC]:
        ffr = p[P_FRIC] * np.tanh(vrel / p[P_VEPS])  # eq C.12, smoothed sign
    # --- force reaching the platen ---------------------------------------------------------
    if fl[F_BACK]:
        d = s[S_XP] - s[S_X]
        g = 0.5 * p[P_GAP]
        fc = 0.0
        if d > g:
            fc = p[P_KC] * (d - g) + p[P_CC] * (s[S_VP] - s[S_V])
        elif d < -g:
            fc = p[P_KC] * (d + g) + p[P_CC] * (s[S_VP] - s[S_V])
        ds[S_XP] = s[S_VP]
        ds[S_VP] = (fh - ffr - fc) / p[P_MP]
        fx = fc
    else:
        fx = fh - ffr
    frod = fx
    fx -= p[P_CPLAT] * (s[S_V] - vf)
    if fl[F_RES]:  # an undeclared mass-spring-damper on the platen (actuator line level)
        fres = p[P_KRES] * (s[S_XR] - s[S_X]) + p[P_CRES] * (s[S_VR] - s[S_V])
        ds[S_XR] = s[S_VR]
        ds[S_VR] = -fres / p[P_MRES]
        fx += fres
    mth = 0.0
    # --- pitch ------------------------------------------------------------------------------
    th = s[S_TH]
    om = s[S_OM]
    mr = 0.0
    mp = 0.0
    if fl[F_PITCH] == 1:
        mp = -p[P_KTH] * th - p[P_CTH] * om  # eq 8.31
    elif fl[F_PITCH] == 2:
        mr = s[S_MR]
        # eq 8.2 with θ_c = 0
        ds[S_MR] = p[P_IR] * p[P_WR] ** 2 * (-p[P_KR] * th - om) - 2.0 * p[P_XIR] * p[P_WR] * mr
        mp = -p[P_KPAS] * th - p[P_CPAS] * om  # eq 8.6
    mth += mr + mp
    # --- specimen ----------------------------------------------------------------------------
    vbase = 0.0
    if n > 0:
        x0 = N_BASE
        v0 = N_BASE + n
        uu = np.empty(n)
        ud = np.empty(n)
        for i in range(n):
            uu[i] = s[x0 + i] - s[S_X] - hs[i] * th
            ud[i] = s[v0 + i] - s[S_V] - hs[i] * om
        r = np.zeros(n)
        # degradation (F_DEGR): the whole stiffness matrix scaled by
        # 1 - L (1 - exp(-E/E0)), E the energy the specimen's viscous damping has
        # dissipated (state S_E, Ė = u̇ᵀ C u̇)
        ks = 1.0
        if fl[F_DEGR]:
            ks = 1.0 - p[P_DLOSS] * (1.0 - np.exp(-s[S_E] / p[P_DE0]))
        power = 0.0
        for i in range(n):
            acc = 0.0
            dmp = 0.0
            for j in range(n):
                acc += ks * Ks[i, j] * uu[j]
                dmp += Cs[i, j] * ud[j]
            r[i] = acc + dmp
            power += ud[i] * dmp
        if fl[F_DEGR]:
            ds[S_E] = power
        # storey nonlinearities as storey forces f_j acting on drift d_j = u_j - u_{j-1}
        for j in range(n):
            dd = ud[j] - (ud[j - 1] if j > 0 else 0.0)
            fj = 0.0
            if fl[F_ADD]:
                fj += c2s[j] * abs(dd) * dd
            if fl[F_HYST] and hy[j, H_ON] != 0.0:
                iz = N_BASE + 2 * n + j
                z = s[iz]
                az = abs(z)
                uy = hy[j, H_UY]
                zn1 = az ** (hy[j, H_N] - 1.0)  # |z|^(n-1) (1 when n = 1)
                ds[iz] = (dd - hy[j, H_BETA] * abs(dd) * zn1 * z
                          - hy[j, H_GAMMA] * dd * zn1 * az) / uy
                drift = uu[j] - (uu[j - 1] if j > 0 else 0.0)
                fj += (1.0 - hy[j, H_ALPHA]) * hy[j, H_K] * (uy * z - drift)
            if j == 0 and fl[F_YIELD]:
                z = s[S_Z]
                dy = p[P_DY]
                sgn = 1.0 if dd * z >= 0.0 else -1.0
                ds[S_Z] = dd * (1.0 - (abs(z) / dy) ** p[P_BWN] * (0.5 + 0.5 * sgn))
                fj += p[P_K1] * (1.0 - p[P_ALPHA]) * (z - uu[0])
            r[j] += fj
            if j > 0:
                r[j - 1] -= fj
        for i in range(n):
            ds[x0 + i] = s[v0 + i]
            ds[v0 + i] = -r[i] / Ms[i]
            fx += r[i]
            mth += hs[i] * r[i]
            vbase += r[i]
    # --- platen ------------------------------------------------------------------------------
    ds[S_X] = s[S_V]
    if fl[F_PITCH] == 0:
        ax = fx / (p[P_MT] + p[P_MB])
        al = 0.0
    else:
        m11 = p[P_MT] + p[P_MB]
        m12 = p[P_MTE] + p[P_MBH]
        m22 = p[P_I] + p[P_IB]
        det = m11 * m22 - m12 * m12
        ax = (m22 * fx - m12 * mth) / det
        al = (m11 * mth - m12 * fx) / det
        ds[S_TH] = om
    ds[S_V] = ax
    ds[S_OM] = al
    # --- foundation (reaction mass): actuator and friction react on it ----------------------
    af = 0.0
    if fl[F_FOUND]:
        ff = -p[P_KF] * s[S_XF] - p[P_CF] * s[S_VF] - fh + ffr + p[P_CPLAT] * (s[S_V] - vf)
        af = ff / p[P_MF]
        ds[S_XF] = s[S_VF]
        ds[S_VF] = af
    # --- valve: command, spool lag (and delay), orifice, rated-flow cap -----------------------
    u = controller(s, xc, vc, ac, ax, p, fl, ds)
    uc = u
    if fl[F_DELAY]:
        u = udel
    if fl[F_LAG]:
        ds[S_Q] = (u - s[S_Q]) / p[P_TAU]  # first-order spool lag; the state is in flow units
        u = s[S_Q]
    ps0 = p[P_PS]
    qc = u
    if fl[F_ORIFICE]:
        # eq C.14 normalised so that the no-load gain is the linear one
        sg = 1.0 if u >= 0.0 else -1.0
        cc = ps0 - sg * pl
        if fl[F_PUMP] and cc > 0.0:
            # supply sags with the flow: q = a sqrt(C - r q), a = |u|/sqrt(P_s0), so
            # q² + a² r q - a² C = 0
            a2 = u * u / ps0
            r = p[P_PUMP]
            qa = 0.5 * (-a2 * r + np.sqrt(a2 * a2 * r * r + 4.0 * a2 * cc))
            qc = sg * qa
        else:
            root = np.sqrt(abs(cc) / ps0)
            qc = u * root if cc >= 0.0 else -u * root
    if fl[F_SAT]:
        qmax = A * p[P_VMAX]
        if qc > qmax:
            qc = qmax
        elif qc < -qmax:
            qc = -qmax
    q = qc
    # --- oil column (eqs 6.3, B.6, C.6-C.11) ------------------------------------------------
    flow = q - p[P_KCT] * pl - A * vrel
    if fl[F_AIR]:
        pmin = 0.02 * ps0
        p1 = max(0.5 * ps0 + 0.5 * pl, pmin)
        p2 = max(0.5 * ps0 - 0.5 * pl, pmin)
        b1 = 1.0 / (1.0 / p[P_BETA] + p[P_AIR] / (1.4 * p1))
        b2 = 1.0 / (1.0 / p[P_BETA] + p[P_AIR] / (1.4 * p2))
        dpl = 2.0 * (b1 + b2) / p[P_V] * flow
    else:
        dpl = 4.0 * p[P_BETA] / p[P_V] * flow
    ds[S_PL] = dpl
    if fl[F_FFILT]:
        ds[S_PF] = -s[S_PF] / p[P_RC] + dpl  # eq B.4
    aux[A_FH] = fh
    aux[A_ACC] = ax
    aux[A_ALPHA] = al
    aux[A_MR] = mr
    aux[A_MP] = mp
    aux[A_XM] = (s[S_XP] if fl[F_BACK] else s[S_X]) - s[S_XF]
    aux[A_VM] = vrel
    aux[A_AF] = af
    aux[A_QCMD] = qc
    aux[A_U] = u
    aux[A_VBASE] = vbase
    aux[A_UC] = uc
    aux[A_ROD] = frod


@njit(cache=True)
def _delayed(uh, j, i0):
    """The valve command at half step j from the history of whole steps up to i0 (a half
    step between two stored whole steps is their mean; the newest one is held)."""
    if j < 0:
        return 0.0
    if j % 2 == 1:
        return 0.5 * (uh[j - 1] + uh[j + 1]) if j + 1 <= i0 else uh[j - 1]
    return uh[j]


@njit(cache=True)
def integrate(p, fl, Ms, Ks, Cs, hs, c2s, hy, s0, xc, vc, ac, dt, nsteps, every, ndelay):
    """RK4 at step dt; the command is given at half steps (xc[2k] at t_k, xc[2k+1] at
    t_k + dt/2), with its velocity vc and acceleration ac. Returns states, aux and state
    derivatives every `every` steps (from step 0).

    The valve delay is `ndelay` half steps (≥ 2), applied to the valve command u."""
    ns = s0.shape[0]
    nrec = nsteps // every + 1
    S = np.empty((nrec, ns))
    X = np.empty((nrec, N_AUX))
    D = np.empty((nrec, ns))
    s = s0.copy()
    k1 = np.empty(ns)
    k2 = np.empty(ns)
    k3 = np.empty(ns)
    k4 = np.empty(ns)
    tmp = np.empty(ns)
    aux = np.empty(N_AUX)
    dummy = np.empty(N_AUX)
    # valve-command history at half steps (for the delay)
    uh = np.zeros(2 * nsteps + 3)
    rec = 0
    for k in range(nsteps + 1):
        t = k * dt
        i0 = 2 * k
        ud0 = _delayed(uh, i0 - ndelay, i0 - 2) if fl[F_DELAY] else 0.0
        rhs(t, s, xc[i0], vc[i0], ac[i0], ud0, p, fl, Ms, Ks, Cs, hs, c2s, hy, k1, aux)
        uh[i0] = aux[A_UC]  # the controller's output at t_k, from the current state
        ud1 = 0.0
        ud2 = 0.0
        if fl[F_DELAY]:
            ud1 = _delayed(uh, i0 + 1 - ndelay, i0)
            ud2 = _delayed(uh, i0 + 2 - ndelay, i0)
        if k % every == 0:
            S[rec, :] = s
            X[rec, :] = aux
            D[rec, :] = k1
            rec += 1
        if k == nsteps:
            break
        for i in range(ns):
            tmp[i] = s[i] + 0.5 * dt * k1[i]
        rhs(t + 0.5 * dt, tmp, xc[i0 + 1], vc[i0 + 1], ac[i0 + 1], ud1, p, fl, Ms, Ks, Cs, hs,
            c2s, hy, k2, dummy)
        for i in range(ns):
            tmp[i] = s[i] + 0.5 * dt * k2[i]
        rhs(t + 0.5 * dt, tmp, xc[i0 + 1], vc[i0 + 1], ac[i0 + 1], ud1, p, fl, Ms, Ks, Cs, hs,
            c2s, hy, k3, dummy)
        for i in range(ns):
            tmp[i] = s[i] + dt * k3[i]
        rhs(t + dt, tmp, xc[i0 + 2], vc[i0 + 2], ac[i0 + 2], ud2, p, fl, Ms, Ks, Cs, hs, c2s,
            hy, k4, dummy)
        for i in range(ns):
            s[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    return S, X, D
