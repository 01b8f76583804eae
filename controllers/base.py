"""The controller protocol: plain Python objects stepped with the physics.

Every control step the simulator hands a controller the sensor vector
``s = [extension (n), velocity (n)]`` of all n force actuators (m, m/s, in the order of
`BuiltModel.force_actuators`, extension positive when the actuator lengthens) and the DOF
commands ``c = [x, z, roll, pitch, twist]`` (m, rad); the controller returns the forces
(N, + pushes the actuator longer) of the actuators it drives for the coming step.

A controller that is linear (ż = A z + B_s s + B_c c, u = C z + D_s s + D_c c) subclasses
`LinearController`: the simulator then discretizes it exactly, fuses it with the others
into one matrix product per step, and the linearizer reads its Jacobian directly.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from vtable.analytic.hold import first_order_hold

DOFS = ("x", "z", "roll", "pitch", "twist")


@runtime_checkable
class Controller(Protocol):
    """What the simulator needs from a controller."""

    actuators: tuple[str, ...]  # names of the force actuators it drives

    def bind(self, actuator_names: tuple[str, ...]) -> None:
        """Learn the simulator's actuator order (called once before running)."""

    def reset(self) -> None:
        """Zero the internal state (the table at rest)."""

    def step(self, dt: float, s: np.ndarray, c: np.ndarray) -> np.ndarray:
        """Forces (N) for `actuators` over the coming step of length dt."""


class LinearController:
    """A linear time-invariant controller given by continuous matrices.

    Subclasses set `actuators`, `state_names` and, in `bind`, the matrices
    A, Bs, Bc, C, Ds, Dc against the full sensor vector.
    """

    actuators: tuple[str, ...] = ()
    state_names: tuple[str, ...] = ()
    #: the units of `state_names` (`vtable.units`; empty: "1" each)
    state_units: tuple[str, ...] = ()
    A: np.ndarray
    Bs: np.ndarray
    Bc: np.ndarray
    C: np.ndarray
    Ds: np.ndarray
    Dc: np.ndarray

    def bind(self, actuator_names: tuple[str, ...]) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def reset(self) -> None:
        self.z = np.zeros(len(self.state_names))
        self._disc = None

    def discrete(self, dt: float) -> dict[str, np.ndarray]:
        """Exact discretization matched to MuJoCo's semi-implicit Euler.

        MuJoCo's qvel_k is the average velocity over the step that ended at t_k
        (x_k = x_{k-1} + dt·v_k), so sensed velocities are held over that step while
        positions and commands vary linearly (first-order hold):

            z_k = Az z_{k-1} + Zp s_{k-1} + Zs s_k + Zc0 c_{k-1} + Zc1 c_k

        and the force for the coming step is the instantaneous force at t_k (MuJoCo's
        kick v_{k+1} = v_k + dt·a_k is the leapfrog midpoint rule), with the velocity at
        t_k estimated as v̂ = 1.5 v_k - 0.5 v_{k-1}:

            u_k = Cz z_k + Up s_{k-1} + Us s_k + Uc1 c_k + Uc2 c_{k+1}

        (s = [extension; velocity] of all actuators). Second-order accurate in dt.
        """
        n = self.A.shape[0]
        ns = self.Bs.shape[1]
        na = ns // 2
        nc = self.Bc.shape[1]
        B = np.hstack([self.Bs, self.Bc])
        # z(dt) per w(0) (gam) and per w(dt) - w(0) (lam), w linear over the step
        Az, gam, lam = first_order_hold(self.A, B, dt)
        X, V, Cc = slice(0, na), slice(na, ns), slice(ns, ns + nc)
        zeros, zeros_like = np.zeros, np.zeros_like
        Zp, Zs = zeros((n, ns)), zeros((n, ns))
        Zp[:, X] = gam[:, X] - lam[:, X]
        Zs[:, X] = lam[:, X]
        Zs[:, V] = gam[:, V]  # v_k held over [t_{k-1}, t_k]
        Zc0, Zc1 = gam[:, Cc] - lam[:, Cc], lam[:, Cc]
        Dx, Dv, Dc = self.Ds[:, X], self.Ds[:, V], self.Dc
        nu = self.C.shape[0]
        Up, Us = zeros((nu, ns)), zeros((nu, ns))
        Us[:, X] = Dx
        Us[:, V] = 1.5 * Dv
        Up[:, V] = -0.5 * Dv
        Uc1, Uc2 = Dc, zeros_like(Dc)
        return {"Az": Az, "Zp": Zp, "Zs": Zs, "Zc0": Zc0, "Zc1": Zc1, "Cz": self.C,
                "Up": Up, "Us": Us, "Uc1": Uc1, "Uc2": Uc2}

    def step(self, dt: float, s: np.ndarray, c: np.ndarray) -> np.ndarray:
        """Stand-alone stepping (the simulator fuses linear controllers instead); the next
        command is extrapolated from the last two."""
        if getattr(self, "_disc", None) is None or self._disc[0] != dt:
            self._disc = (dt, self.discrete(dt))
            self._prev = None
        d = self._disc[1]
        s_prev, c_prev = (s, c) if self._prev is None else self._prev
        self.z = d["Az"] @ self.z + d["Zp"] @ s_prev + d["Zs"] @ s + d["Zc0"] @ c_prev \
            + d["Zc1"] @ c
        self._prev = (s.copy(), c.copy())
        return (d["Cz"] @ self.z + d["Up"] @ s_prev + d["Us"] @ s + d["Uc1"] @ c
                + d["Uc2"] @ (2 * c - c_prev))

    def _index(self, actuator_names: tuple[str, ...]) -> tuple[np.ndarray, int]:
        n = len(actuator_names)
        try:
            idx = np.array([actuator_names.index(a) for a in self.actuators], dtype=int)
        except ValueError as e:
            raise ValueError(f"{type(self).__name__}: actuator missing from the model: {e}") \
                from None
        return idx, n
