"""The tables vtable models, built once from the presets with the report's formulas: the
EERC table (`virtual_table`), a run's declared table (`virtual_table_for`: the EERC table
as described, or a uniaxial platen) and the rigid bodies on them (`bodies`). Every model
reads the one description they make (`vtable.params.virtual.VirtualTable`)."""

from vtable.tables.eerc import describe, virtual_table, with_rocking
from vtable.tables.lab import uniaxial_table, virtual_table_for

__all__ = ["describe", "uniaxial_table", "virtual_table", "virtual_table_for", "with_rocking"]
