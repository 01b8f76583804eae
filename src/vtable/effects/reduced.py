"""The fast reduced model the diagnosis fits: the planar table (x, and θ with
pitch_flexibility) with its specimen, one equivalent horizontal actuator carrying the
servo effects (compiled kernel), and the foundation and sensor effects.

Mechanics come from the same assembly as the virtual table's linear model
(`analytic.virtual_table.mechanics`); the servo from the same kernel as the virtual
table's controller; effect parameters from the same `Physics`.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.signal

from vtable.analytic.virtual_table import mechanics
from vtable.effects import physics as phys
from vtable.effects.kernel import simulate_reduced
from vtable.effects.sensor import sensor_filter
from vtable.errors import VtableError
from vtable.params.virtual import VirtualTable, split_rocking, virtual_table
from vtable.runs.model import Run

#: the largest integration step (RK4); a run of step dt is integrated at dt / ceil(dt / SIM_DT)
SIM_DT = 0.0025

#: the channels the reduced model predicts (format names)
PREDICTED = ("avg_hdisp", "h1_disp", "h2_disp", "h3_disp", "h_vel", "avg_hacc", "h1_force",
             "h2_force", "h3_force", "pitch_disp", "pitch_acc", "acc_n_ne", "acc_n_nw",
             "pot_n_sw", "pot_n_se")


def pitch_loop_state(vt: VirtualTable, nq: int):
    """The pitch DOF loop of the vertical actuators (servo.py's law with θ_c = 0, no RC)
    as one state p, the DOF pressure: ṗ = (4β/V)(-k_t g (θ + k_p p) - k_ct p - A θ̇),
    moment on θ: -A ΣT² p (T_i = lever arms). Coordinate 1 is θ."""
    s = vt.vertical_servo
    g, p_scale, _ = vt.gain_scales("pitch")
    lever = vt.table.geometry.vertical_square / 2
    sum_t2 = 4 * lever**2
    c0 = 4 * s.beta / s.volume
    Aw = np.array([[-c0 * (s.k_t * g * s.k_p * p_scale + s.k_ct)]])
    Wq = np.zeros((1, nq))
    Wv = np.zeros((1, nq))
    Wq[0, 1] = -c0 * s.k_t * g
    Wv[0, 1] = -c0 * s.area
    Fw = np.zeros((nq, 1))
    Fw[1, 0] = s.area * sum_t2
    return Aw, Wq, Wv, Fw


class ReducedModel:
    """Predicts a run's channels from its command for a given `Physics`."""

    def __init__(self, physics: phys.Physics, vt: VirtualTable | None = None) -> None:
        self.physics, self.vt = physics, vt or virtual_table()
        ph, vt = self.physics, self.vt
        M, K, C, _, names, slides, pos = mechanics(vt, ph.specimen)
        keep = [0] + ([3] if ph.has("pitch_flexibility") else []) + \
            list(range(5, 5 + len(slides)))
        M, K, C = (X[np.ix_(keep, keep)] for X in (M, K, C))
        self.coords = [names[i] for i in keep]
        n = len(keep)
        na = 0
        self.Aw = np.zeros((0, 0))
        if ph.has("pitch_flexibility"):
            # the virtual table's own pitch system: stabilizers retuned to (k_θ, c_θ) plus
            # the vertical actuators' pitch DOF loop as one auxiliary state
            k_s, c_s = split_rocking(*phys.rocking_spring(ph), vt)
            d_p = vt.table.geometry.stabilizer_square
            K[1, 1] += k_s * d_p**2
            C[1, 1] += c_s * d_p**2
            na = 1
            self.Aw, Wq, Wv, Fw = pitch_loop_state(vt, n)
        if na == 0:
            Wq = Wv = np.zeros((0, n))
            Fw = np.zeros((n, 0))
        c2 = np.zeros(n)
        if slides:
            c2[n - len(slides):] = phys.quadratic_damping(ph, ph.specimen)
        bF = np.zeros(n)
        bF[0] = 1.0
        ax = np.zeros(n)
        ax[0] = 1.0
        if ph.has("foundation_compliance"):
            m_f, k_f, c_f = phys.foundation(ph, vt)
            M, K, C = (np.pad(X, ((0, 1), (0, 1))) for X in (M, K, C))
            M[-1, -1], K[-1, -1], C[-1, -1] = m_f, k_f, c_f
            c2, bF, ax = np.append(c2, 0.0), np.append(bF, -1.0), np.append(ax, -1.0)
            Wq, Wv = np.pad(Wq, ((0, 0), (0, 1))), np.pad(Wv, ((0, 0), (0, 1)))
            Fw = np.pad(Fw, ((0, 1), (0, 0)))
            self.coords.append("x_f")
        self.Wq, self.Wv, self.Fw = Wq, Wv, Fw
        self.M, self.K, self.C, self.c2, self.bF, self.ax = M, K, C, c2, bF, ax
        self.Minv = np.linalg.inv(M)
        self.sp = phys.servo_vector(ph, vt, phys.N_HORIZONTAL)
        gx, px, vx = vt.gain_scales("horizontal")
        self.g = np.array([gx])
        self.kp = np.array([self.sp[5] * px])
        self.kv = np.array([self.sp[6] * vx])
        self.T = np.ones((1, 1))
        self.slides = slides
        self.h_top = float(pos[slides[-1].name][2]) if slides else 0.0

    def simulate(self, t: np.ndarray, x_c: np.ndarray) -> dict[str, np.ndarray]:
        """Channels (SI) on the uniform time grid `t` of a command x_c sampled on it.

        Any uniform step dt works: the model integrates at h = dt/m, m = ⌈dt/SIM_DT⌉ (the
        largest step ≤ 2.5 ms that divides dt: 2.5 ms at 200 Hz, 1/512 s at 256 Hz, 1 ms at
        1 kHz), the command interpolated to that grid by a polyphase FIR
        (`scipy.signal.resample_poly`), and returns every m-th sample."""
        t = np.asarray(t, dtype=float)
        if len(t) < 2:
            raise VtableError("the model needs a command of at least two samples")
        dt = float((t[-1] - t[0]) / (len(t) - 1))
        if not dt > 0:
            raise VtableError(f"run step {dt:g} s: the time column must increase")
        up = max(1, math.ceil(dt / SIM_DT - 1e-9))
        h = dt / up
        xc = scipy.signal.resample_poly(x_c, up, 1)[: (len(t) - 1) * up + 1] if up > 1 \
            else np.ascontiguousarray(x_c, dtype=float)
        nq = self.M.shape[0]
        Q, Qd, Qdd, F = simulate_reduced(xc, h, nq, self.Minv, self.K, self.C, self.c2,
                                         self.bF, self.ax, self.sp, self.T, self.T, self.g,
                                         self.kp, self.kv, self.Aw, self.Wq, self.Wv, self.Fw)
        ip = self.coords.index("pitch") if "pitch" in self.coords else None
        ns = len(self.slides)
        s0 = 1 + (ip is not None)
        drift = Q[:, s0:s0 + ns].sum(axis=1) if ns else np.zeros(len(xc))
        drift_a = Qdd[:, s0:s0 + ns].sum(axis=1) if ns else np.zeros(len(xc))
        th = Q[:, ip] if ip is not None else np.zeros(len(xc))
        th_a = Qdd[:, ip] if ip is not None else np.zeros(len(xc))
        x_a = Q @ self.ax
        out = {"avg_hdisp": x_a, "h_vel": Qd[:, 0], "avg_hacc": Qdd[:, 0], "pitch_disp": th,
               "pitch_acc": th_a, "h1_force": F / phys.N_HORIZONTAL}
        if ns:
            out["acc_n_ne"] = Qdd[:, 0] + self.h_top * th_a + drift_a
            out["pot_n_sw"] = Q[:, 0] + self.h_top * th + drift
        if self.physics.has("sensor_filter"):
            fc = self.physics.effects["sensor_filter"]["cutoff_hz"]
            out = {k: sensor_filter(v, 1.0 / h, fc) for k, v in out.items()}
        out = {k: v[::up] for k, v in out.items()}
        for i in (1, 2, 3):
            out[f"h{i}_disp"] = out["avg_hdisp"]
        out["h2_force"] = out["h3_force"] = out["h1_force"]
        if ns:
            out["acc_n_nw"] = out["acc_n_ne"]
            out["pot_n_se"] = out["pot_n_sw"]
        return out

    def predict(self, run: Run) -> dict[str, np.ndarray]:
        """The run's predictable channels, from its command (h_span)."""
        return self.simulate(run.time, run.channel("h_span"))
