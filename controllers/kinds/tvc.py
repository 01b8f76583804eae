"""``tvc``: three-variable control as digital controllers do it — displacement, velocity
and acceleration feedback, a second-order reference generator whose velocity and
acceleration feed forward, optional ΔP stabilisation and notches (`digital`)."""

from vtable.controllers.kinds.base import ControllerKind
from vtable.controllers.kinds.digital import DIGITAL, digital_params

KIND = ControllerKind(
    "tvc", "displacement, velocity and acceleration feedback with a reference generator "
    "and feedforward",
    keys=("i", "d", "derivative_filter", "feedforward_velocity", "feedforward_acceleration",
          "acceleration_gain", "reference_frequency", "reference_damping", "notches"),
    stage=DIGITAL, params=digital_params,
    calibrated={"t_v": (0.5, 2.0, "s"), "t_a": (0.5, 2.0, "s2"), "k_a": (0.5, 2.0, "s2")})
