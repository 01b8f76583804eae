"""Servo controllers stepped with the physics (installed as ``vtable.controllers``).

A controller is a plain Python object (`Controller`): the simulator gives it the
actuators' extensions and velocities and the DOF commands every control step, and it
returns actuator forces. `standard_controllers` gives the EERC table's: the linear
servo-hydraulic loops of every actuator with the five DOF controllers at the Table 3.2
knob settings, and the cross-connected passive stabilizers.
"""

from vtable.controllers.base import DOFS, Controller, LinearController
from vtable.controllers.nonlinear import NonlinearValveServo, ValveParams
from vtable.controllers.servo import ServoController, dof_matrix
from vtable.controllers.stabilizers import PassiveStabilizers


def standard_controllers(vt, rc_filter=("x", "twist")) -> list:
    """The EERC table's controllers for the virtual table `vt`."""
    return [ServoController(vt, rc_filter=rc_filter), PassiveStabilizers(vt)]


def nonlinear_controllers(vt, valve: ValveParams | None = None) -> list:
    """Appendix C valves on H1-H3, linear loops on V1-V4, passive stabilizers."""
    return [NonlinearValveServo(vt, valve), ServoController(vt, groups=("vertical",)),
            PassiveStabilizers(vt)]


__all__ = ["DOFS", "Controller", "LinearController", "NonlinearValveServo", "PassiveStabilizers",
           "ServoController", "ValveParams", "dof_matrix", "nonlinear_controllers",
           "standard_controllers"]
