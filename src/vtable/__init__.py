"""vtable: a physics-based virtual shaking table after report UCB/EERC-91/13."""

__version__ = "0.1.0"
