"""Measured runs: the CSV + TOML interchange format (and HDF5 with the same content)."""

from vtable.runs.format import FORMAT, dumps_toml, specimen_table
from vtable.runs.model import FORMAT_UNITS, Run
from vtable.runs.read import campaign, read_any, read_hdf5, read_run, write_hdf5, write_run

__all__ = ["FORMAT", "FORMAT_UNITS", "Run", "campaign", "dumps_toml", "read_any", "read_hdf5",
           "read_run", "specimen_table", "write_hdf5", "write_run"]
