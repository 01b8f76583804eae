"""The servo-hydraulic actuator, written once (report ch. 6, app. B).

Below both `vtable.effects` and `vtable.controllers`: the DOF servo law of eqs 6.1-6.4
(`law.ServoLaw`), the actuator's linear constants (the table's `ServoConstants`), the
compiled element that steps a group of actuators (`element.servo_rates`,
`element.servo_step`), and the stages effects add to it (`stage.Stage`: valve, flow,
pressure, feedback and force laws), compiled per stage set (`compose.composition`).
"""

from vtable.hydraulics.compose import Composition, composition
from vtable.hydraulics.element import constants_vector, servo_rates, servo_step
from vtable.hydraulics.law import ServoLaw, group_law
from vtable.hydraulics.stage import Stage, add_stage

__all__ = [
           "Composition",
           "ServoLaw",
           "Stage",
           "add_stage",
           "composition",
           "constants_vector",
           "group_law",
           "servo_rates",
           "servo_step",
]
