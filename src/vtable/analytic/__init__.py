"""Analytical state-space models of the report, one `LinearModel` API."""

from vtable.analytic.base import LinearModel, Mode, Modes
from vtable.analytic.margins import Margins
from vtable.analytic.mdof import MDOFHybrid
from vtable.analytic.mechanical import MechanicalModel
from vtable.analytic.pitch import HybridModel, TwoDirectionalTable
from vtable.analytic.rcfilter import RCFilterServo
from vtable.analytic.sdof import TableSDOF
from vtable.analytic.servo import (
    ServoLoop,
    loop_row,
    open_loop_from_servo,
    servo_from_open_loop,
)

__all__ = [
    "HybridModel", "LinearModel", "MDOFHybrid", "Margins", "MechanicalModel", "Mode", "Modes",
    "RCFilterServo", "ServoLoop", "TableSDOF", "TwoDirectionalTable", "loop_row",
    "open_loop_from_servo", "servo_from_open_loop",
]
