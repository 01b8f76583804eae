"""The multibody virtual table built with MjSpec."""

from vtable.mjcf.builder import SLAB_JOINTS, BuiltModel, build, check_specimen

__all__ = ["SLAB_JOINTS", "BuiltModel", "build", "check_specimen"]
