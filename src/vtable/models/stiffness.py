"""The stiffness of a force law left without `stiffness=`: its largest slope dF/dd over a
probe of relative displacements from a micron to half a metre, either sign, at rest (the
models step finely enough for the stiff mode it makes with its mass). A law that cannot be
probed, or whose slope is not finite, is refused in one line."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from vtable.controllers.force_law import law_argument, law_params
from vtable.errors import VtableError, interrupted

#: |d| probed (m): 1 µm to 0.5 m, 8 points a decade, either sign, and 0
PROBE = np.concatenate([[0.0], np.logspace(-6, math.log10(0.5), 46)])


def needed_stiffness(law: Callable, params: Sequence[float], states: int = 0) -> float:
    """max |dF/dd| of `law(d, v, z, p, dz)` over `PROBE` (central differences), N/m."""
    p = law_argument(*law_params(params))
    name = getattr(law, "__name__", "the force law")
    slope = 0.0
    try:
        for d0 in np.concatenate([PROBE, -PROBE[1:]]):
            h = max(1e-9, 1e-4 * abs(d0))
            f = [float(law(float(d0 + s * h), 0.0, np.zeros(states), p, np.zeros(states)))
                 for s in (-1.0, 1.0)]
            s = abs(f[1] - f[0]) / (2 * h)
            if not math.isfinite(s):
                raise VtableError(f"{name}: give stiffness= (N/m, its largest slope): the "
                                  f"law's force at d = {d0:.3g} m is not finite")
            slope = max(slope, s)
    except VtableError:
        raise
    except Exception as e:  # a user's law may raise anything
        if interrupted(e):
            raise KeyboardInterrupt from e
        raise VtableError(f"{name}: give stiffness= (N/m, its largest slope): probing the law "
                          f"failed ({type(e).__name__}: {e})") from None
    return slope
