"""Servo controllers stepped with the physics (installed as ``vtable.controllers``).

The multibody table and its controllers arrive with the virtual-table issue; the
controllers will read the same parameter objects as the analytical models
(`vtable.params.ServoConstants`, `vtable.params.ControlSettings`).
"""
