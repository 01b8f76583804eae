"""Measured runs: the CSV + TOML interchange format (and HDF5 with the same content)."""

from vtable.runs.format import FORMAT, CommandDescription, dumps_toml, specimen_table
from vtable.runs.hdf5 import read_hdf5, write_hdf5
from vtable.runs.meta import Declaration
from vtable.runs.model import FORMAT_UNITS, Run, channel_dimension
from vtable.runs.read import campaign, read_any, read_run
from vtable.runs.table import TABLE_PRESETS, TableDescription, table_from_dict
from vtable.runs.write import write_run

__all__ = ["FORMAT", "FORMAT_UNITS", "TABLE_PRESETS", "CommandDescription", "Declaration",
           "Run", "TableDescription", "campaign", "channel_dimension", "dumps_toml",
           "read_any", "read_hdf5", "read_run", "specimen_table", "table_from_dict",
           "write_hdf5", "write_run"]
