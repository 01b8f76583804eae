"""Interaction with yielding (ch. 9 extended to a hysteretic specimen): the ductility demand
and residual drift of a yielding SDOF specimen with and without the table's interaction,
across a sweep of its period.

For each period T the specimen is retuned (f_s = 1/T; its weight, height, damping and
declared hysteresis kept: a yield drift stays that drift, a yield strength that strength,
`Hysteresis.of_storey`) and played twice under the same command:

- **fixed base**: the specimen alone on an ideal table, m (ü + ẍ_c) + c u̇ + k u − F_h = 0,
  F_h the Bouc–Wen force of `vtable.analytic.hysteresis.bouc_wen` (the law written once),
  integrated by scipy's RK45 with ẍ_c linear between samples;
- **on the table**: the reduced model of the table carrying it (the standard table's loop
  and pitch system, `vtable.models.reduced.ReducedModel`), driven by x_c.

Ductility μ = max|u| / u_y; the residual drift is the mean drift over the last second of
`TAIL` seconds of rest appended to the record (the table held at its last command).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from vtable.analytic.hysteresis import bouc_wen
from vtable.controllers.force_law import law_argument, law_params
from vtable.errors import VtableError
from vtable.models.reduced import ReducedModel
from vtable.params.specimen import SDOFSpecimen
from vtable.params.virtual import VirtualTable
from vtable.sim.run import standard_physics

TAIL = 5.0  # s of rest after the record, for the residual drift
SETTLED = 1.0  # s at the end over which the residual drift is averaged


@dataclass(frozen=True)
class DuctilitySweep:
    """Per period (s): ductility and residual drift (m), fixed base and on the table."""

    periods: np.ndarray
    ductility_fixed: np.ndarray
    ductility_table: np.ndarray
    residual_fixed: np.ndarray
    residual_table: np.ndarray
    held: str  # "yield drift" or "yield strength": what the sweep keeps as declared

    def to_json(self) -> dict:
        return {"periods_s": self.periods.tolist(), "held": self.held,
                "ductility": {"fixed_base": self.ductility_fixed.tolist(),
                              "on_table": self.ductility_table.tolist()},
                "residual_drift_m": {"fixed_base": self.residual_fixed.tolist(),
                                     "on_table": self.residual_table.tolist()}}


def _with_tail(t: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    dt = float(t[1] - t[0])
    n = round(TAIL / dt)
    return (np.concatenate([t, t[-1] + dt * np.arange(1, n + 1)]),
            np.concatenate([x, np.full(n, x[-1])]))


def fixed_base_drift(spec: SDOFSpecimen, t: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """The yielding specimen's drift u(t) on an ideal table under command acceleration
    `acc` (m/s², on the uniform grid t)."""
    h = spec.hysteresis
    u_y, alpha = h.of_storey(1, spec.stiffness)
    p = law_argument(*law_params({"k": spec.stiffness, "alpha": alpha, "u_y": u_y,
                                  "beta": h.beta, "gamma": h.gamma, "n": h.n}))
    m, c, k = spec.mass, spec.damping_coefficient, spec.stiffness
    dz = np.zeros(1)
    t0, dt, last = float(t[0]), float(t[1] - t[0]), len(t) - 2
    slope = np.diff(acc) / dt

    def rhs(tt: float, y: np.ndarray) -> list[float]:
        u, v = y[0], y[1]
        f_h = bouc_wen(u, v, y[2:], p, dz)
        i = min(max(int((tt - t0) / dt), 0), last)
        a_c = acc[i] + slope[i] * (tt - t0 - i * dt)
        return [v, -a_c - (c * v + k * u - f_h) / m, dz[0]]

    sol = solve_ivp(rhs, (t[0], t[-1]), np.zeros(3), t_eval=t, max_step=dt,
                    rtol=1e-7, atol=[1e-9, 1e-8, 1e-9])
    if not sol.success:
        raise VtableError(f"the fixed-base yielding specimen did not integrate: {sol.message}")
    return sol.y[0]


def sweep(spec: SDOFSpecimen, t: np.ndarray, x_c: np.ndarray, acc: np.ndarray,
          periods, vt: VirtualTable | None = None) -> DuctilitySweep:
    """`DuctilitySweep` of the yielding SDOF `spec` under the command x_c (m) with its
    acceleration `acc` (m/s²) on the uniform grid t, over `periods` (s)."""
    if not isinstance(spec, SDOFSpecimen) or spec.hysteresis is None:
        raise VtableError("the ductility sweep needs a sdof specimen with [specimen.hysteresis]")
    tt, xx = _with_tail(t, x_c)
    _, aa = _with_tail(t, acc)
    aa[len(t):] = 0.0
    n_end = round(SETTLED / (t[1] - t[0]))
    out = {k: [] for k in ("mf", "mt", "rf", "rt")}
    for T in np.asarray(periods, dtype=float):
        s = dataclasses.replace(spec, frequency=1.0 / T)
        u_y = s.hysteresis.of_storey(1, s.stiffness)[0]
        u_f = fixed_base_drift(s, tt, aa)
        u_t = ReducedModel(standard_physics(s, None, vt)).simulate(tt, xx)["floor1_drift"]
        out["mf"].append(np.max(np.abs(u_f)) / u_y)
        out["mt"].append(np.max(np.abs(u_t)) / u_y)
        out["rf"].append(float(np.mean(u_f[-n_end:])))
        out["rt"].append(float(np.mean(u_t[-n_end:])))
    held = "yield drift" if spec.hysteresis.yield_drift is not None else "yield strength"
    return DuctilitySweep(np.asarray(periods, dtype=float), *(np.array(out[k]) for k in
                                                               ("mf", "mt", "rf", "rt")), held)
