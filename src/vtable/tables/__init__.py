"""The tables vtable models, built once from the presets with the report's formulas: the
EERC table (`virtual_table`), a lab's declared table (`described_table`: the EERC table
as described, or a uniaxial platen), the bare table's loop (`bare_loop`) and the rigid
bodies on them (`bodies`). Every model reads the one description they make
(`vtable.params.virtual.VirtualTable`)."""

from vtable.tables.eerc import describe, virtual_table, with_rocking
from vtable.tables.lab import bare_loop, described_table, uniaxial_table

__all__ = ["bare_loop", "describe", "described_table", "uniaxial_table", "virtual_table",
           "with_rocking"]
