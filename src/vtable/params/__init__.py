"""Typed parameter objects (SI inside) with the report's presets."""

from vtable.params import loops, presets, specimen, table
from vtable.params.base import Params, read_toml
from vtable.params.loops import *  # noqa: F403  (each module's __all__)
from vtable.params.specimen import *  # noqa: F403
from vtable.params.table import *  # noqa: F403

__all__ = ["Params", "presets", "read_toml", *loops.__all__, *specimen.__all__, *table.__all__]
