"""Closed-loop linearization of the multibody table (mechanics by MuJoCo's
`mjd_transitionFD`, controllers by their own matrices; controller state kept outside
MuJoCo).

The discrete closed loop is exactly what the simulator steps: sensors at state k,
controller output (the fused, step-averaged form) applied over the step, MuJoCo's
integrator to k+1. Its eigenvalues μ give continuous-time λ = log(μ)/dt.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import mujoco
import numpy as np

from vtable.analytic.base import Modes, modes_of
from vtable.mjcf.builder import BuiltModel
from vtable.sim.simulator import Simulator


@dataclass(frozen=True)
class Linearization:
    """Discrete closed loop X_{k+1} = Φ X_k + Γ0 c_{k-1} + Γ1 c_k + Γ2 c_{k+1} at step dt, its
    continuous-time eigenvalues, and output rows for the slab joints (qpos)."""

    Phi: np.ndarray
    Gamma0: np.ndarray
    Gamma1: np.ndarray
    Gamma2: np.ndarray
    C_qpos: np.ndarray
    dt: float
    eigenvalues: np.ndarray

    def modes(self) -> Modes:
        return modes_of(self.eigenvalues)

    def freqresp(self, f_hz, qpos_index: int, dof: int = 0) -> np.ndarray:
        """qpos[qpos_index] / command[dof] at frequencies f_hz, from the discrete loop."""
        f = np.asarray(f_hz, dtype=float)
        z = np.exp(2j * np.pi * f * self.dt)
        n = self.Phi.shape[0]
        out = np.empty(len(f), dtype=complex)
        for i, zi in enumerate(z):
            g = self.Gamma0[:, dof] / zi + self.Gamma1[:, dof] + self.Gamma2[:, dof] * zi
            out[i] = self.C_qpos[qpos_index] @ np.linalg.solve(zi * np.eye(n) - self.Phi, g)
        return out


def linearize(built: BuiltModel, controllers=None, dt: float = 1e-4,
              eps: float = 1e-6) -> Linearization:
    """Linearize the closed loop about rest at MuJoCo timestep `dt` (small, so that the
    discrete map approximates the continuous system closely)."""
    model = _with_timestep(built, dt)
    sim = Simulator(_rebuilt(built, model), controllers)
    d = mujoco.MjData(model)
    mujoco.mj_resetData(model, d)
    n = sim.n
    d.ctrl[:] = 0.0
    d.ctrl[n] = built.pit_force
    mujoco.mj_forward(model, d)
    nx = 2 * model.nv + model.na
    A = np.zeros((nx, nx))
    B = np.zeros((nx, model.nu))
    C = np.zeros((model.nsensordata, nx))
    D = np.zeros((model.nsensordata, model.nu))
    mujoco.mjd_transitionFD(model, d, eps, True, A, B, C, D)
    Cs = C[: 2 * n]  # tendon lengths and velocities (the controllers' sensors)
    nz, ns = sim.nz, 2 * n
    M = sim.M  # [u_k; z_k] = M [z_{k-1}; s_{k-1}; s_k]
    Mu_z, Mu_p, Mu_s = M[:n, :nz], M[:n, nz:nz + ns], M[:n, nz + ns:]
    Mz_z, Mz_p, Mz_s = M[n:, :nz], M[n:, nz:nz + ns], M[n:, nz + ns:]
    # closed-loop state X_k = [x_k, z_{k-1}, s_{k-1}]
    N = nx + nz + ns
    Phi = np.zeros((N, N))
    Bu = B[:, :n]
    Phi[:nx, :nx] = A + Bu @ Mu_s @ Cs
    Phi[:nx, nx:nx + nz] = Bu @ Mu_z
    Phi[:nx, nx + nz:] = Bu @ Mu_p
    Phi[nx:nx + nz, :nx] = Mz_s @ Cs
    Phi[nx:nx + nz, nx:nx + nz] = Mz_z
    Phi[nx:nx + nz, nx + nz:] = Mz_p
    Phi[nx + nz:, :nx] = Cs
    G0, G1, G2 = (np.zeros((N, sim.N0.shape[1])) for _ in range(3))
    for G, Nk in ((G0, sim.N0), (G1, sim.N1), (G2, sim.N2)):
        G[:nx] = Bu @ Nk[:n]
        G[nx:nx + nz] = Nk[n:]
    Cq = np.zeros((model.nq, N))
    Cq[:, : model.nq] = np.eye(model.nq)  # hinge/slide joints only: qpos is the first nv
    mu = np.linalg.eigvals(Phi)
    mu = mu[np.abs(mu) > 1e-12]  # the s_{k-1} copies of position-only sensors
    return Linearization(Phi, G0, G1, G2, Cq, dt, np.log(mu.astype(complex)) / dt)


def _with_timestep(built: BuiltModel, dt: float) -> mujoco.MjModel:
    spec = built.spec.copy()
    spec.option.timestep = dt
    spec.assets = dict(built.assets)
    return spec.compile()


def _rebuilt(built: BuiltModel, model: mujoco.MjModel) -> BuiltModel:
    return replace(built, model=model)
