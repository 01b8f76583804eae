"""Rendering of what other modules computed (installed as ``vtable.viz``)."""
