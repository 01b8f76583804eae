"""Simulating the virtual table: stepping, channels, limits, linearization."""

from vtable.sim.simulator import (
    Exceedance,
    SimResult,
    SimulationDiverged,
    Simulator,
    check_commands,
)

__all__ = ["Exceedance", "SimResult", "SimulationDiverged", "Simulator", "check_commands"]
