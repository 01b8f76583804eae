"""actuator_friction: Coulomb friction in the horizontal actuators and bearings,
F_r sign(ẋ) (app. C, eq C.12), smoothed as F_r tanh(ẋ/v_ε) with v_ε = 1 mm/s; F_r is the
total over the actuators."""

from __future__ import annotations

from vtable.effects.base import Effect, Param


class ActuatorFriction(Effect):
    name = "actuator_friction"
    physics = "Coulomb friction in the actuators and bearings, F_r sign(ẋ)"
    section = "app. C (eq C.12)"
    signature = ("small spans lose more than large ones; distortion at motion reversals; "
                 "force offsets")
    params = (Param("friction", "kip", 1.0, 0.01, 30.0, log=True,
                    source="assumed; total over the horizontal actuators"),)

    def apply(self, m, p):
        m.set_servo(friction=p["friction"])


EFFECT = ActuatorFriction()
