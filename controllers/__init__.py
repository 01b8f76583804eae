"""Servo controllers stepped with the physics (installed as ``vtable.controllers``).

A controller is a plain Python object (`Controller`): the simulator gives it the
actuators' extensions and velocities and the DOF commands every control step, and it
returns actuator forces. `standard_controllers` gives the EERC table's: the linear
servo-hydraulic loops of every actuator with the five DOF controllers at the Table 3.2
knob settings, and the cross-connected passive stabilizers. The servo law itself lives
in `vtable.hydraulics` (written once, shared with the reduced model).
"""

from vtable.controllers.base import DOFS, Controller, LinearController
from vtable.controllers.force_law import ForceLawController, quadratic_damper
from vtable.controllers.hydraulic import HydraulicServo
from vtable.controllers.servo import ServoController, dof_matrix
from vtable.controllers.stabilizers import PassiveStabilizers
from vtable.hydraulics import appendix_c, group_law


def standard_controllers(vt, rc_filter=("x", "twist")) -> list:
    """The table's controllers for the virtual table `vt` (the EERC table's: every loop,
    and the passive stabilizers). A loop with a valve lag is stepped by the hydraulic
    element (`HydraulicServo`)."""
    if vt.valve_lag:
        ctl = [HydraulicServo(vt), ServoController(vt, groups=("vertical",))]
    else:
        ctl = [ServoController(vt, rc_filter=rc_filter)]
    return ctl + ([PassiveStabilizers(vt)] if vt.stabilizers.pairs else [])


def nonlinear_controllers(vt, **valve) -> list:
    """Appendix C valves on H1-H3 (`vtable.hydraulics.appendix_c`: orifice flow from the
    supply pressure, rated-flow cap; `valve` passes air_ratio, friction, ...), linear
    loops on V1-V4, passive stabilizers."""
    base = group_law(vt, "horizontal").hydraulics
    hyd = appendix_c(base, vt.table.geometry.supply_pressure, vt.table.rated_flow("H1"),
                     **valve)
    return [HydraulicServo(vt, hyd), ServoController(vt, groups=("vertical",))] + \
        ([PassiveStabilizers(vt)] if vt.stabilizers.pairs else [])


__all__ = ["DOFS", "Controller", "ForceLawController", "HydraulicServo", "LinearController",
           "PassiveStabilizers", "ServoController", "dof_matrix", "nonlinear_controllers",
           "quadratic_damper", "standard_controllers"]
