"""actuator_friction: Coulomb friction in the horizontal actuators and bearings,
F_r sign(ẋ) (app. C, eq C.12), smoothed as F_r tanh(ẋ/v_ε) with v_ε = 1 mm/s; F_r is the
total over the actuators — a force stage of the hydraulic element."""

from __future__ import annotations

import math

from vtable.effects.base import Effect, Param
from vtable.hydraulics.stage import Stage

V_EPS = 1e-3  # m/s: the smoothing velocity v_ε


def coulomb(F, v, p):
    """F - F_r tanh(v/v_ε) (eq C.12, smoothed): p.friction per actuator, p.v_eps."""
    return F - p.friction * math.tanh(v / p.v_eps)


FRICTION = Stage("coulomb_friction", "force", coulomb, ("friction", "v_eps"),
                 extensive=("friction",))


class ActuatorFriction(Effect):
    name = "actuator_friction"
    physics = "Coulomb friction in the actuators and bearings, F_r sign(ẋ)"
    section = "app. C (eq C.12)"
    signature = ("small spans lose more than large ones; distortion at motion reversals; "
                 "force offsets")
    params = (Param("friction", "kip", 1.0, 0.01, 30.0, log=True,
                    source="assumed; total over the horizontal actuators"),)
    stages = (FRICTION,)

    def apply(self, m, p):
        m.add_stage(FRICTION, friction=p["friction"] / m.table.n_horizontal, v_eps=V_EPS)


EFFECT = ActuatorFriction()
