"""``three_variable``: the report's analog loop (eqs 6.1-6.4): P on the displacement
error, velocity and ΔP feedback — Table 3.2's knob positions or the physical gains; its
terms are all in the element's P law, so it adds no stage unless notches are declared."""

from vtable.controllers.kinds.base import ControllerKind
from vtable.controllers.kinds.digital import DIGITAL, digital_params

KIND = ControllerKind(
    "three_variable", "the report's analog loop: P on the displacement error, velocity and "
    "ΔP feedback (eqs 6.1-6.4)",
    keys=("gain", "delta_p", "rate", "notches"),
    stage=DIGITAL, params=digital_params)
