"""vtable: a physics-based virtual shaking table after report UCB/EERC-91/13.

numba's cache folder is chosen by `vtable._numba`, imported by the modules that compile
kernels (not here: ``import vtable`` does no work)."""

__version__ = "0.1.0"
