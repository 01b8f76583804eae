"""Measured runs: the CSV + TOML interchange format."""

from vtable.runs.format import FORMAT, dumps_toml, specimen_table, write_run

__all__ = ["FORMAT", "dumps_toml", "specimen_table", "write_run"]
