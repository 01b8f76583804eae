"""Stepping the MuJoCo table with the Python controllers.

Each control step: `mj_step1` (positions, velocities, tendon lengths and sensors at the
current state), the controllers compute actuator forces from the actuator extensions and
velocities and the DOF commands, then `mj_step2` integrates. Linear controllers are
fused into one matrix product per step (`LinearController.discrete`); any other
controller is called through its `step` method.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

from vtable import units
from vtable.controllers import DOFS, Controller, LinearController, standard_controllers
from vtable.errors import VtableError
from vtable.interpolate import upsample
from vtable.mjcf.builder import SLAB_JOINTS, BuiltModel
from vtable.params.limits import check_motion
from vtable.sim.stepping import mujoco_steps, sparse_rows, step_linear

CHECK_EVERY = 250  # steps between the divergence checks (Python loop)
CHUNK = 1000  # steps of the compiled loop between the divergence checks


class SimulationDivergedError(VtableError):
    """The simulation blew up; nothing was written."""


@dataclass(frozen=True)
class Exceedance:
    """An actuator beyond a rated limit: first time, peak and the limit (SI)."""

    actuator: str
    quantity: str  # "stroke" | "velocity" | "force"
    first_time: float
    peak: float
    limit: float

    def __str__(self) -> str:
        unit = {"stroke": "in", "velocity": "in/s", "force": "kip"}[self.quantity]
        return (f"{self.actuator} {self.quantity} {units.from_si(self.peak, unit):.3g} {unit} "
                f"exceeds {units.from_si(self.limit, unit):.3g} {unit} from t = "
                f"{self.first_time:.3f} s")


@dataclass
class SimResult:
    """Recorded histories at the output rate (SI) plus limit exceedances."""

    built: BuiltModel
    t: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    qacc: np.ndarray
    forces: np.ndarray  # (n_t, n_actuators), N: what each actuator applies to the platen
    extension: np.ndarray  # (n_t, n_actuators), m
    ext_velocity: np.ndarray
    sensors: np.ndarray  # full sensordata at the output rate
    commands: np.ndarray  # (n_t, 5) DOF commands
    command_acc: np.ndarray  # (n_t,) x command acceleration
    controller_states: np.ndarray
    controller_state_names: tuple[str, ...]
    exceedances: list[Exceedance] = field(default_factory=list)
    #: (n_t, n_actuators), N: each actuator's piston force A·P_L (equal to `forces` but
    #: where a controller's force stages, e.g. friction, make them differ)
    pressure_forces: np.ndarray | None = None
    #: the units of `controller_state_names` (`vtable.units`)
    controller_state_units: tuple[str, ...] = ()
    #: an OpenSees specimen's recorded floors and wrench (`OpenSeesController.history`)
    specimen: dict[str, np.ndarray] | None = None

    def joint(self, name: str, what: str = "qpos") -> np.ndarray:
        """A joint's history; a locked slab joint (left out of the model) is zero."""
        m = self.built.model
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        if j < 0:
            if name in SLAB_JOINTS:
                return np.zeros(len(self.t))
            raise VtableError(f"no joint {name!r}")
        adr = m.jnt_qposadr[j] if what == "qpos" else m.jnt_dofadr[j]
        return getattr(self, what)[:, adr]

    def sensor(self, name: str) -> np.ndarray:
        m = self.built.model
        i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, name)
        if i < 0:
            raise VtableError(f"no sensor {name!r}")
        a, n = m.sensor_adr[i], m.sensor_dim[i]
        return self.sensors[:, a:a + n]


def resample_commands(t: np.ndarray, commands: Mapping[str, np.ndarray],
                      t_new: np.ndarray) -> np.ndarray:
    """DOF commands (name -> history on `t`) linearly interpolated on `t_new` (n, 5)."""
    unknown = set(commands) - set(DOFS)
    if unknown:
        raise VtableError(f"unknown command DOF {sorted(unknown)[0]!r}; expected "
                          f"{', '.join(DOFS)}")
    out = np.zeros((len(t_new), len(DOFS)))
    for k, v in commands.items():
        v = np.asarray(v, dtype=float)
        if v.shape != t.shape:
            raise VtableError(f"command {k!r} has {v.size} samples for {t.size} times")
        if not np.all(np.isfinite(v)):
            raise VtableError(f"command {k!r} has non-finite samples")
        out[:, DOFS.index(k)] = _resampled(t, v, t_new)
    return out


def _resampled(t: np.ndarray, v: np.ndarray, t_new: np.ndarray) -> np.ndarray:
    """v on t_new: band-limited (`vtable.interpolate.upsample`) when both grids are uniform
    from the same start and t_new is an integer number of times finer (the command
    on the control step), else linear."""
    dt, dt_new = (t[-1] - t[0]) / (len(t) - 1), (t_new[-1] - t_new[0]) / max(len(t_new) - 1, 1)
    up = round(dt / dt_new) if dt_new > 0 else 0
    if (up > 1 and abs(up * dt_new - dt) < 1e-9 * dt and abs(t_new[0] - t[0]) < 1e-9 * dt
            and np.allclose(np.diff(t), dt, rtol=1e-6, atol=0)):
        fine = upsample(v, up)
        if len(fine) >= len(t_new):
            return fine[:len(t_new)]
    return np.interp(t_new, t, v)


def check_commands(built: BuiltModel, t: np.ndarray, cmd: np.ndarray) -> None:
    """Refuse commands beyond the table's displacement or velocity (Table 2.2;
    `vtable.params.limits.check_motion`)."""
    for dof in ("x", "z"):
        check_motion(built.vt, t, cmd[:, DOFS.index(dof)], f"{dof} command", dof)


class Simulator:
    """The virtual table `built` driven by `controllers` at `control_dt` = the MuJoCo
    timestep (1 kHz by default)."""

    def __init__(self, built: BuiltModel, controllers: Sequence[Controller] | None = None
                 ) -> None:
        self.built = built
        self.model = built.model
        self.dt = float(self.model.opt.timestep)
        self.controllers = list(controllers) if controllers is not None else \
            standard_controllers(built.vt)
        names = built.force_actuators
        driven = [a for c in self.controllers for a in c.actuators]
        dup = {a for a in driven if driven.count(a) > 1}
        if dup:
            raise VtableError(f"actuator {sorted(dup)[0]} is driven by two controllers")
        self.n = len(names)
        self.data = mujoco.MjData(self.model)
        for c in self.controllers:
            c.bind(names)
            if hasattr(c, "attach"):  # a controller that reads or pushes the bodies itself
                c.attach(self.model, self.data)
        mujoco.mj_forward(self.model, self.data)
        self.rest_length = self.data.actuator_length[: self.n].copy()
        self._fuse()

    def _fuse(self) -> None:
        """Block matrices of all linear controllers (see `LinearController.discrete`):

            [u_k; z_k] = M [z_{k-1}; s_{k-1}; s_k] + N0 c_{k-1} + N1 c_k + N2 c_{k+1}
        """
        n, lin = self.n, [c for c in self.controllers if isinstance(c, LinearController)]
        self.linear, self.other = lin, [c for c in self.controllers if c not in lin]
        sizes = [len(c.state_names) for c in lin]
        nz = sum(sizes)
        ns = 2 * n
        M = np.zeros((n + nz, nz + 2 * ns))
        N0, N1, N2 = (np.zeros((n + nz, len(DOFS))) for _ in range(3))
        off = 0
        names = self.built.force_actuators
        P, S = slice(nz, nz + ns), slice(nz + ns, nz + 2 * ns)
        for c, k in zip(lin, sizes, strict=True):
            d = c.discrete(self.dt)
            idx = [names.index(a) for a in c.actuators]
            zr = n + off + np.arange(k)
            zc = slice(off, off + k)
            M[zr, zc] = d["Az"]
            M[zr, P] = d["Zp"]
            M[zr, S] = d["Zs"]
            N0[zr], N1[zr] = d["Zc0"], d["Zc1"]
            Cz = d["Cz"]  # u_k = Cz z_k + ..., z_k substituted
            M[idx, zc] += Cz @ d["Az"]
            M[idx, P] += Cz @ d["Zp"] + d["Up"]
            M[idx, S] += Cz @ d["Zs"] + d["Us"]
            N0[idx] += Cz @ d["Zc0"]
            N1[idx] += Cz @ d["Zc1"] + d["Uc1"]
            N2[idx] += d["Uc2"]
            off += k
        self.M, self.N0, self.N1, self.N2, self.nz = M, N0, N1, N2, nz
        # extension = length - rest length, in both s_{k-1} and s_k
        rest = np.concatenate([self.rest_length, np.zeros(n)])
        self.offset = -(M[:, P] + M[:, S]) @ rest
        self.state_names = tuple(s for c in lin for s in c.state_names)
        self.state_units = tuple(u for c in lin
                                 for u in (c.state_units or ("1",) * len(c.state_names)))

    def run(self, t: np.ndarray, commands: Mapping[str, np.ndarray], *, output_dt: float = 0.005,
            check: bool = True, max_extension: float | None = None) -> SimResult:
        """Simulate the command histories (DOF name -> array on `t`, SI) from rest."""
        t = np.asarray(t, dtype=float)
        if t.ndim != 1 or len(t) < 2 or np.any(np.diff(t) <= 0):
            raise VtableError("command time must be increasing with at least two samples")
        dt = self.dt
        n_steps = int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
        tk = t[0] + np.arange(n_steps) * dt
        cmd = resample_commands(t, commands, tk)
        if check:
            check_commands(self.built, tk, cmd)
        dec = max(1, round(output_dt / dt))
        if abs(dec * dt - output_dt) > 1e-9 * output_dt:
            raise VtableError(f"output_dt {output_dt:g} s is not a multiple of the control step "
                              f"{dt:g} s")
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        for c in self.controllers:
            c.reset()
        n, nz = self.n, self.nz
        d.ctrl[n] = self.built.pit_force
        ns = 2 * n
        # full-rate history rows [s_k, z_k, u_k]; the flat slice from row k-1 to the s of
        # row k is [s_{k-1}, z_{k-1}, u_{k-1}, s_k], the input of one matrix product
        W = ns + nz + n
        M2 = np.zeros((nz + n, W + ns))
        M2[:, :ns] = np.vstack([self.M[n:, nz:nz + ns], self.M[:n, nz:nz + ns]])
        M2[:, ns:ns + nz] = np.vstack([self.M[n:, :nz], self.M[:n, :nz]])
        M2[:, W:] = np.vstack([self.M[n:, nz + ns:], self.M[:n, nz + ns:]])
        # the command terms, rows ordered as M2's [z; u]: N0 c_{k-1} + N1 c_k + N2 c_{k+1}
        perm = np.r_[n:n + nz, 0:n]
        Nall = np.hstack([self.N0, self.N1, self.N2])[perm]
        offset = np.ascontiguousarray(self.offset[perm])
        hist = np.zeros((n_steps + 1, W))  # row 0: the state before the first step
        flat = hist.reshape(-1)
        n_out = (n_steps - 1) // dec + 1
        rec = {"qpos": np.empty((n_out, m.nq)), "qvel": np.empty((n_out, m.nv)),
               "qacc": np.empty((n_out, m.nv)), "sensors": np.empty((n_out, m.nsensordata))}
        limit_x = max_extension or _far(self.built.vt)
        sens = d.sensordata
        ctrl = d.ctrl
        other = self.other
        names = self.built.force_actuators
        other_idx = [[names.index(a) for a in c.actuators] for c in other]
        rest = self.rest_length
        pressure = np.full((n_out, n), np.nan)  # A·P_L where a controller reports it
        step1, step2, dot = mujoco.mj_step1, mujoco.mj_step2, np.dot
        U = slice(ns + nz, W)
        fns = None if other else mujoco_steps()
        if fns is not None:  # linear controllers only: the compiled loop (`stepping`)
            args = (sparse_rows(M2), sparse_rows(Nall), offset, cmd, hist, ns, n, dec, sens,
                    ctrl, d.qpos, d.qvel, d.qacc, rec["qpos"], rec["qvel"], rec["qacc"],
                    rec["sensors"])
            for k0 in range(0, n_steps, CHUNK):
                k1 = min(n_steps, k0 + CHUNK)
                step_linear(*fns, m._address, d._address, k0, k1, *args)
                self._check_finite(tk[k1 - 1], limit_x)
        else:
            prev = np.vstack([cmd[:1], cmd[:-1]])
            nxt = np.vstack([cmd[1:], cmd[-1:]])
            ck = np.hstack([prev, cmd, nxt]) @ Nall.T + offset
        for k in range(n_steps if fns is None else 0):
            row = hist[k + 1]
            step1(m, d)
            row[:ns] = sens[:ns]
            if k == 0:
                hist[0, :ns] = row[:ns]
            out = row[ns:]
            dot(M2, flat[k * W:(k + 1) * W + ns], out=out)
            out += ck[k]
            ctrl[:n] = row[U]
            if other:
                s_k = row[:ns].copy()
                s_k[:n] -= rest
                for c, idx in zip(other, other_idx, strict=True):
                    ctrl[idx] = c.step(dt, s_k, cmd[k])
                    if k % dec == 0 and hasattr(c, "pressure_force"):
                        pressure[k // dec, idx] = c.pressure_force()
                row[U] = ctrl[:n]
            if k % dec == 0:
                i = k // dec
                rec["qpos"][i] = d.qpos
                rec["qvel"][i] = d.qvel
            step2(m, d)
            if k % dec == 0:
                rec["qvel"][i] += d.qvel  # v(t_k) = mean of the step averages around t_k
                rec["qacc"][i] = d.qacc
                rec["sensors"][i] = sens
            if k % CHECK_EVERY == 0:
                self._check_finite(tk[k], limit_x)
        self._check_finite(tk[-1], limit_x)
        rec["qvel"] *= 0.5
        full = hist[1:]
        ext_all = full[:, :ns].copy()
        ext_all[:, :n] -= rest
        forces_all = full[:, U]
        out_idx = np.arange(0, n_steps, dec)
        # the actuators' velocity at t_k as the joints' (rec["qvel"]): the mean of the step
        # averages around t_k (each row holds the average over the step ending there)
        ev = ext_all[:, n:]
        ext_vel = 0.5 * (ev[out_idx] + ev[np.minimum(out_idx + 1, len(ev) - 1)])
        res = SimResult(built=self.built, t=tk[out_idx], qpos=rec["qpos"], qvel=rec["qvel"],
                        qacc=rec["qacc"], forces=forces_all[out_idx].copy(),
                        extension=ext_all[out_idx, :n], ext_velocity=ext_vel,
                        sensors=rec["sensors"], commands=cmd[out_idx],
                        command_acc=np.gradient(np.gradient(cmd[:, 0], dt), dt)[out_idx],
                        controller_states=full[out_idx, ns:ns + nz].copy(),
                        controller_state_names=self.state_names,
                        controller_state_units=self.state_units)
        res.pressure_forces = np.where(np.isnan(pressure), res.forces, pressure)
        for c in self.controllers:
            if hasattr(c, "history"):
                res.specimen = c.history(out_idx)
        res.exceedances = exceedances(self.built, tk, ext_all, forces_all)
        return res

    def _check_finite(self, t: float, limit_x: float) -> None:
        d, m = self.data, self.model
        bad = d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0
        if bad or not np.all(np.isfinite(d.qpos)) or not np.all(np.isfinite(d.qvel)):
            raise SimulationDivergedError(f"simulation diverged at t = {t:.3f} s: non-finite "
                                     "state (unstable control settings?); nothing written")
        ext = d.actuator_length[: self.n] - self.rest_length
        i = int(np.argmax(np.abs(ext)))
        if abs(ext[i]) > limit_x:
            name = self.built.force_actuators[i]
            raise SimulationDivergedError(
                f"simulation diverged at t = {t:.3f} s: actuator {name} at "
                f"{units.from_si(ext[i], 'in'):.3g} in, far beyond any stroke it has (unstable "
                "control settings?); nothing written")
        del m


def exceedances(built: BuiltModel, t: np.ndarray, ext_all: np.ndarray,
                forces: np.ndarray) -> list[Exceedance]:
    """Stroke (±stroke/2), velocity (rated flow / area) and force (capacity) exceedances
    per actuator, from the full-rate histories; nothing is clipped."""
    out = []
    n = forces.shape[1]
    known = {a.name for a in built.vt.actuators}
    for i, name in enumerate(built.force_actuators):
        if name not in known:  # internal actuators (structure dampers) have no ratings
            continue
        a = built.vt.actuator(name)
        checks = [("stroke", ext_all[:, i], a.stroke / 2)] if a.stroke else []
        checks.append(("force", forces[:, i], a.capacity))
        if a.flow:
            checks.append(("velocity", ext_all[:, n + i], a.flow / a.area))
        for what, x, lim in checks:
            over = np.abs(x) > lim
            if np.any(over):
                out.append(Exceedance(name, what, float(t[np.argmax(over)]),
                                      float(np.max(np.abs(x))), lim))
    return out


def _far(vt) -> float:
    """m: an actuator extension that can only be a diverged simulation — twice the longest
    declared stroke, or ten times the platen's own width when no stroke is declared (a
    lab's table that gives none: any command is played)."""
    strokes = [a.stroke for a in vt.actuators if a.stroke]
    return 2 * max(strokes) if strokes else 10 * vt.table.geometry.plan_width
