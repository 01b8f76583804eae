"""The servo-hydraulic actuator, written once (report ch. 6, app. B, app. C).

Below both `vtable.effects` and `vtable.controllers`: the DOF servo law of eqs 6.1-6.4
(`law.ServoLaw`), the actuator's physical constants and the appendix C options by name
(`element.HydraulicParams`), the compiled element that steps a group of actuators
(`element.servo_rates`, `element.servo_step`), and the appendix C valve set
(`valve.appendix_c`).
"""

from vtable.hydraulics.element import HydraulicParams, servo_rates, servo_step
from vtable.hydraulics.law import ServoLaw, group_law
from vtable.hydraulics.valve import appendix_c

__all__ = ["HydraulicParams", "ServoLaw", "appendix_c", "group_law", "servo_rates",
           "servo_step"]
