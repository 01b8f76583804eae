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
from vtable.effects.actuator_friction import FRICTION, V_EPS
from vtable.effects.flow_saturation import FLOW_CAP
from vtable.effects.force_feedback_filter import RC_FILTER
from vtable.effects.oil_column_air import AIR
from vtable.effects.valve_dynamics import SPOOL_LAG
from vtable.effects.valve_flow_nonlinearity import ORIFICE
from vtable.hydraulics.law import group_law


def _table_stages(vt) -> list:
    """The table's own stages on H1-H3: its RC filter on the ΔP feedback (eq B.4), its
    servovalves' lag and its digital controller's terms (a lab table's)."""
    out = [(RC_FILTER, {"rc": vt.horizontal_servo.rc})] if vt.horizontal_servo.rc else []
    out += [vt.control.use] if vt.control is not None else []
    return out + ([(SPOOL_LAG, {"tau": vt.valve_lag})] if vt.valve_lag else [])


def standard_controllers(vt, rc: bool = True) -> list:
    """The table's controllers for the virtual table `vt` (the EERC table's: every loop,
    and the passive stabilizers): the horizontal loop with the table's own stages — its RC
    filter on the ΔP feedback (eq B.4; left out when not `rc`) and a lab table's valve lag
    — both linear, so every loop is one fused linear controller."""
    stages = [st for st in _table_stages(vt) if rc or st[0] is not RC_FILTER]
    law = group_law(vt, "horizontal", stages=tuple(stages)) if vt.group("horizontal") else None
    ctl = [ServoController(vt, laws={"horizontal": law} if law is not None else None)]
    return ctl + ([PassiveStabilizers(vt)] if vt.stabilizers.pairs else [])


def nonlinear_controllers(vt, air_ratio: float = 0.0, friction: float = 0.0) -> list:
    """Appendix C valves on H1-H3 — the stages of the valve_flow_nonlinearity (orifice
    flow from the table's supply pressure) and flow_saturation (the rated flow) effects,
    optionally oil_column_air's (`air_ratio`) and actuator_friction's (`friction`, N per
    actuator), with the table's RC filter — linear loops on V1-V4, passive stabilizers."""
    ps = vt.table.geometry.supply_pressure
    stages = [*_table_stages(vt), (ORIFICE, {"supply_pressure": ps}),
              (FLOW_CAP, {"max_flow": vt.table.rated_flow("H1")})]
    if air_ratio:
        stages.append((AIR, {"air_ratio": air_ratio, "mean_pressure": ps}))
    if friction:
        stages.append((FRICTION, {"friction": friction, "v_eps": V_EPS}))
    return [HydraulicServo(vt, stages=tuple(stages)), ServoController(vt, groups=("vertical",))] \
        + ([PassiveStabilizers(vt)] if vt.stabilizers.pairs else [])


__all__ = ["DOFS", "Controller", "ForceLawController", "HydraulicServo", "LinearController",
           "PassiveStabilizers", "ServoController", "dof_matrix", "nonlinear_controllers",
           "quadratic_damper", "standard_controllers"]
