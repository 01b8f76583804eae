"""Simulating the virtual table: stepping, channels, limits, linearization."""

from vtable.sim.simulator import (
    Exceedance,
    SimResult,
    SimulationDivergedError,
    Simulator,
    check_commands,
)

__all__ = ["Exceedance", "SimResult", "SimulationDivergedError", "Simulator", "check_commands"]
