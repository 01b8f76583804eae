"""A lab's own controller kind: the report's P loop plus a leaky integral of the
displacement error, k_i/(s + 1/T_l) — an integrator that forgets over T_l, as some
digital controllers use so that a long test does not wind up a drift.

Load it with ``--controller-from examples/leaky_pi_controller.py`` and declare it:

    [table.controller]
    kind = "leaky_pi"
    displacement_gain_v_per_m = 129.93
    p = 1.0
    integral_gain_per_s = 1.5
    leak_time_s = 20.0
"""

from vtable.controllers.kinds import ControllerKind, register
from vtable.errors import VtableError
from vtable.hydraulics import Stage


def leaky_pi(u, xc, x, v, z, p, dz):
    """The drive per unit P gain: u (the P law's, the error in metres) plus the leaky
    integral z[0] of the error, d z[0]/dt = e - z[0]/T_l."""
    e = xc - x
    dz[0] = e - z[0] / p.t_l
    return u + p.k_i * z[0]


LEAKY_PI = Stage("leaky_pi", "control", leaky_pi, ("k_i", "t_l"), states=1, linear=True)


def leaky_pi_params(c) -> dict[str, float]:
    """The stage's parameters per unit P gain, from the declared controller (SI)."""
    p = c.p if c.p is not None else 1.0
    if not p > 0:
        raise VtableError("[table.controller].p: a leaky_pi controller needs p > 0")
    if c.extra["leak_time_s"] <= 0:
        raise VtableError("[table.controller].leak_time_s: must be > 0")
    return {"k_i": c.extra["integral_gain_per_s"] / p, "t_l": c.extra["leak_time_s"]}


register(ControllerKind(
    "leaky_pi", "P on the displacement error plus a leaky integral k_i/(s + 1/T_l)",
    stage=LEAKY_PI, params=leaky_pi_params, calibrated={"k_i": (0.5, 2.0, "1/s")},
    user_keys={"integral_gain_per_s": "1/s", "leak_time_s": "s"}))
