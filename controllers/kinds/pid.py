"""``pid``: PID on the displacement error with a filtered derivative, velocity and
acceleration feedforward of the command, optional ΔP stabilisation, velocity and
acceleration feedback, and notches (`digital`)."""

from vtable.controllers.kinds.base import ControllerKind
from vtable.controllers.kinds.digital import DIGITAL, digital_params

KIND = ControllerKind(
    "pid", "PID on the displacement error, feedforward of the command's velocity and "
    "acceleration",
    keys=("i", "d", "derivative_filter", "feedforward_velocity", "feedforward_acceleration",
          "acceleration_gain", "notches"),
    stage=DIGITAL, params=digital_params,
    calibrated={"t_v": (0.5, 2.0, "s"), "t_a": (0.5, 2.0, "s2")})
