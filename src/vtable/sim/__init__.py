"""Simulating the virtual table: `simulate` (the one way), stepping, channels, limits,
linearization."""

from vtable.sim.run import SimulatedRun, simulate, standard_physics
from vtable.sim.simulator import (
    Exceedance,
    SimResult,
    SimulationDivergedError,
    Simulator,
    check_commands,
)

__all__ = ["Exceedance", "SimResult", "SimulatedRun", "SimulationDivergedError", "Simulator",
           "check_commands", "simulate", "standard_physics"]
