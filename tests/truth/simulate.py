"""Simulate a table + specimen under a command and return the clean channels (SI)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import signal

from . import constants as c
from . import model as m
from .build import CONNECTION_HZ, Built, build
from .commands import Command
from .errors import TruthError
from .linearize import jacobian
from .specimens import Specimen
from .tables import Table

DT_MAX = 5e-4  # s, largest internal step
# s, largest internal step with Bouc–Wen storeys: ż has a kink at each reversal of the drift
# rate (|u̇|), where RK4 drops to about second order; at 0.25 ms an El Centro run's drift is
# within ≈ 6e-7 of its converged value (≈ 3e-6 at 0.5 ms; elastic runs ≈ 1e-8)
DT_MAX_HYSTERESIS = 2.5e-4


@dataclass
class Result:
    """Clean channels on the output grid, in SI (m, m/s, m/s², N, rad, rad/s²).

    Displacements h*_disp/avg_hdisp and h_vel are the actuators' (piston relative to the
    reaction mass); avg_hacc is the platen's absolute acceleration at the actuator line;
    h*_force is A·ΔP per actuator; v*_force and p*_stab are the dynamic increments (the
    static weight is carried by the pit air pressure, §2.2); pot_*/floor*_disp are absolute.
    With the table's force_measured = "load_cell", h*_force is the force the rod transmits
    to the platen: A·ΔP less the actuator friction (eq C.12), or the piston-platen
    connection force when the piston is a body of its own (backlash); the platen's own
    viscous damping and a platen resonator act after the load cell.

    `sensors` maps each channel to the physical sensor group it belongs to; channels of
    the same quantity measured by different sensors (h1_disp..h3_disp, acc_n_ne/acc_n_nw,
    pot_n_sw/pot_n_se) get independent noise in `write_run`. `internal` holds truth
    quantities that are not measured (x_t, θ, P_L, storey drift, base shear, ...).

    A specimen with Bouc–Wen storeys adds floorK_drift (storey K's drift, floor K minus
    floor K-1 in the storey springs' coordinate u_i = x_i - x_t - h_i θ) and floorK_shear
    (-Σ_{j≥K} m_j a_j, + resisting + drift) for every storey K, and internal zK (the
    hysteretic variable of each yielding storey). internal driftK and drift_velK are every
    storey's drift and drift rate."""

    t: np.ndarray
    fs: float
    channels: dict[str, np.ndarray]
    internal: dict[str, np.ndarray]
    table: Table
    specimen: Specimen
    command: Command
    dt: float
    built: Built
    notes: list[str] = field(default_factory=list)


def _steps(fs: float, duration: float, dt_max: float) -> tuple[int, int, float]:
    if not (isinstance(fs, int | float) and fs > 0):
        raise TruthError(f"simulate: fs must be a positive sample rate, got {fs!r}")
    n_out = math.floor(duration * fs + 1e-9) + 1
    n_sub = max(1, math.ceil(1.0 / (fs * dt_max) - 1e-9))
    return n_out, n_sub, 1.0 / (fs * n_sub)


def stable_step(table: Table, spec: Specimen) -> float:
    """Largest internal step: 0.5 ms (0.25 ms with Bouc–Wen storeys), or less when the
    fastest linearised root λ (valve lag, friction smoothing, backlash connection ...) needs
    it: |λ| dt ≤ 2 (RK4 is stable to ≈ 2.8 on both axes)."""
    b = build(table, spec, 0.0)
    rho = float(np.max(np.abs(np.linalg.eigvals(jacobian(b)[0]))))
    if b.fl[m.F_BACK]:
        rho = max(rho, 2 * np.pi * CONNECTION_HZ)
    dt_max = DT_MAX_HYSTERESIS if b.fl[m.F_HYST] else DT_MAX
    return min(dt_max, 2.0 / rho)


def _sensor_filter(x: np.ndarray, dt: float, cutoff_hz: float) -> np.ndarray:
    """4-pole Butterworth analog low-pass (§2.3), discretised exactly for inputs that are
    linear between samples (first-order hold), applied along axis 0."""
    A, B, C, D = signal.zpk2ss(*signal.butter(4, 2 * np.pi * cutoff_hz, analog=True,
                                              output="zpk"))
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete((A, B, C, D), dt, method="foh")
    z, p, k = signal.ss2zpk(Ad, Bd, Cd, Dd)
    sos = signal.zpk2sos(z, p, k)
    return signal.sosfilt(sos, x, axis=0)


def _mount(x: np.ndarray, dt: float, f_m: float, zeta_m: float, f_c: float) -> np.ndarray:
    """The accelerometer's mount (poles of s² + 2ζω_m s + ω_m², unit static gain) times a
    2-pole Butterworth at f_c, as poles and gain, discretised exactly for inputs linear
    between samples (first-order hold)."""
    wm = 2 * np.pi * f_m
    _, pb, kb = signal.butter(2, 2 * np.pi * f_c, analog=True, output="zpk")
    poles = np.concatenate([np.roots([1.0, 2 * zeta_m * wm, wm * wm]), pb])
    A, B, C, D = signal.zpk2ss([], poles, kb * wm * wm)
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete((A, B, C, D), dt, method="foh")
    return signal.sosfilt(signal.zpk2sos(*signal.ss2zpk(Ad, Bd, Cd, Dd)), x)


def simulate(table: Table, spec: Specimen, cmd: Command, fs: float = 256.0) -> Result:
    """Run `cmd` on `table` carrying `spec`; channels sampled at `fs` (any rate: the
    internal RK4 step is 1/(fs·n) ≤ 0.5 ms, smaller if `stable_step` asks)."""
    n_out, n_sub, dt = _steps(fs, cmd.duration, stable_step(table, spec))
    built = build(table, spec, dt)
    nsteps = (n_out - 1) * n_sub
    th = np.arange(2 * nsteps + 3) * (0.5 * dt)
    xc, vc = cmd.at(th)
    ac = cmd.acceleration(th) if built.p[m.P_TA] != 0 and not built.fl[m.F_REFG] else (
        np.zeros_like(th))
    filt = table.effects.get("sensor_filter")
    mount = table.effects.get("sensor_mount")
    every = 1 if filt or mount else n_sub
    ndelay = round(2 * built.delay / dt) if built.delay > 0 else 0
    s0 = np.zeros(built.n_state)
    S, X, D = m.integrate(built.p, built.fl, built.Ms, built.Ks, built.Cs, built.hs, built.c2s,
                          built.hy, s0, xc, vc, ac, dt, nsteps, every, ndelay)
    if not np.all(np.isfinite(S)):
        raise TruthError("simulate: the response diverged (unstable configuration)")
    ch, internal = _channels(built, S, X, D)
    if mount:
        ch["avg_hacc"] = _mount(ch["avg_hacc"], dt, mount["f_m"], mount["zeta_m"], mount["f_c"])
    if filt:
        names = list(ch)
        arr = _sensor_filter(np.column_stack([ch[k] for k in names]), dt, filt["cutoff_hz"])
        ch = {k: arr[:, j] for j, k in enumerate(names)}
    if filt or mount:
        ch = {k: v[::n_sub] for k, v in ch.items()}
        internal = {k: v[::n_sub] for k, v in internal.items()}
    t = np.arange(n_out) / fs
    zero = table.effects.get("sensor_offset")
    if zero:
        ch["avg_hacc"] = ch["avg_hacc"] + zero["zero_m_s2"] + zero["drift_m_s3"] * t
    out = {"h_span": xc[0:2 * nsteps + 1:2 * n_sub]}
    out.update(ch)
    return Result(t, float(fs), out, internal, table, spec, cmd, dt, built)


def _channels(b: Built, S: np.ndarray, X: np.ndarray, D: np.ndarray):
    tab = b.table
    n = int(b.fl[m.F_N])
    ch: dict[str, np.ndarray] = {}
    na = tab.actuators
    xm, vm = X[:, m.A_XM], X[:, m.A_VM]
    for i in range(1, na + 1):
        ch[f"h{i}_disp"] = xm
    ch["avg_hdisp"] = xm
    ch["h_vel"] = vm
    ch["avg_hacc"] = D[:, m.S_V]
    force = X[:, m.A_ROD] if b.fl[m.F_LOADCELL] else X[:, m.A_FH]
    for i in range(1, na + 1):
        ch[f"h{i}_force"] = force / na
    if tab.pitch != "none":
        ch["pitch_acc"] = D[:, m.S_OM]
        ch["pitch_disp"] = S[:, m.S_TH]
    if tab.pitch == "two_directional":
        # positive θ lowers the +x side; M_y = -Σ x_i F_i; pattern ∓ on the ±x actuators
        fv = X[:, m.A_MR] / (4 * c.EERC_VERTICAL_ARM)
        fp = X[:, m.A_MP] / (4 * c.EERC_STABILIZER_ARM)
        ch.update({"v1_force": -fv, "v2_force": fv, "v3_force": fv, "v4_force": -fv,
                   "p1_stab": -fp, "p2_stab": fp, "p3_stab": fp, "p4_stab": -fp})
    internal = {"x_t": S[:, m.S_X], "v_t": S[:, m.S_V], "theta": S[:, m.S_TH],
                "omega": S[:, m.S_OM], "m_pitch": X[:, m.A_MR] + X[:, m.A_MP],
                "p_load": S[:, m.S_PL], "x_f": S[:, m.S_XF], "q_cmd": X[:, m.A_QCMD],
                "f_rod": X[:, m.A_ROD], "x_r": S[:, m.S_XR],
                "base_shear": X[:, m.A_VBASE]}
    if n:
        x0, v0 = m.N_BASE, m.N_BASE + n
        top_x, top_a = S[:, x0 + n - 1], D[:, v0 + n - 1]
        ch["acc_n_ne"] = top_a
        ch["acc_n_nw"] = top_a
        ch["pot_n_sw"] = top_x
        ch["pot_n_se"] = top_x
        if b.specimen.kind == "shear_building" and n >= 1:
            for i in range(n):
                ch[f"floor{i + 1}_acc"] = D[:, v0 + i]
                ch[f"floor{i + 1}_disp"] = S[:, x0 + i]
        # storey drifts in the storey springs' coordinate: u_i = x_i - x_t - h_i θ,
        # drift_K = u_K - u_{K-1} (u_0 = 0, the platen)
        u = [S[:, x0 + i] - S[:, m.S_X] - b.hs[i] * S[:, m.S_TH] for i in range(n)]
        ud = [S[:, v0 + i] - S[:, m.S_V] - b.hs[i] * S[:, m.S_OM] for i in range(n)]
        drift = [u[0]] + [u[i] - u[i - 1] for i in range(1, n)]
        for i in range(n):
            internal[f"drift{i + 1}"] = drift[i]
            internal[f"drift_vel{i + 1}"] = ud[i] - (ud[i - 1] if i else 0.0)
        internal["top_rel"] = top_x - S[:, m.S_X] - b.hs[n - 1] * S[:, m.S_TH]
        if b.fl[m.F_HYST]:
            # storey shear, + resisting + drift: -Σ_{j≥K} m_j a_j (absolute accelerations)
            shear = np.zeros_like(top_a)
            shears = []
            for i in range(n - 1, -1, -1):
                shear = shear - b.Ms[i] * D[:, v0 + i]
                shears.append(shear)
            shears.reverse()
            for i in range(n):
                ch[f"floor{i + 1}_drift"] = drift[i]
                ch[f"floor{i + 1}_shear"] = shears[i]
                if b.hy[i, m.H_ON]:
                    internal[f"z{i + 1}"] = S[:, x0 + 2 * n + i]
    return ch, internal
