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
from vtable.hydraulics.law import group_law
from vtable.hydraulics.table_stages import table_stages


def standard_controllers(vt, rc: bool = True) -> list:
    """The table's controllers for the virtual table `vt` (the EERC table's: every loop,
    and the passive stabilizers): the horizontal loop with the table's own stages — its RC
    filter on the ΔP feedback (eq B.4; left out when not `rc`) and a lab table's valve lag
    — both linear, so every loop is one fused linear controller."""
    stages = table_stages(vt, rc)
    law = group_law(vt, "horizontal", stages=tuple(stages)) if vt.group("horizontal") else None
    ctl = [ServoController(vt, laws={"horizontal": law} if law is not None else None)]
    return ctl + ([PassiveStabilizers(vt)] if vt.stabilizers.pairs else [])


__all__ = ["DOFS", "Controller", "ForceLawController", "HydraulicServo", "LinearController",
           "PassiveStabilizers", "ServoController", "dof_matrix",
           "quadratic_damper", "standard_controllers"]
