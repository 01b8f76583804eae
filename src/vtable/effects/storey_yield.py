"""storey_yield: storeys of the specimen yield — the Bouc–Wen storey of
`vtable.analytic.hysteresis` (Wen 1976; Baber & Wen 1981) on storey `storey` and the
`storeys` − 1 above it, with their yield drift u_y, post-yield stiffness ratio α and the
sharpness n of the transition fitted (one set for them all; β = γ = 0.5).

A default candidate of `diagnose` like every catalog effect: it is fitted only where the
runs show amplitude dependence the current model misses (`vtable.diagnose.screen`). Which
storeys yield is a choice, not a distance (`Param(discrete=True)`): the fit tries each
storey alone, then grows the best run of adjacent storeys a storey at a time while that fits
better (`choices`), and keeps the best. Yielding concentrates in adjacent storeys (a storey
mechanism, or the lower storeys of a frame, where the shear is largest); storeys yielding
apart, or at yield drifts far apart, are a user's effect. A bare table or a rigid block has
no storey, and the effect cannot be built there. The report treats the fixed-base parameters
as amplitude-dependent (ch. 3, §5.3's loops); this is that dependence as yielding storeys.
"""

from __future__ import annotations

import numpy as np

from vtable.analytic.hysteresis import add_yielding_storey
from vtable.analytic.structure import storey_masses
from vtable.effects.base import Effect, Param
from vtable.errors import VtableError
from vtable.units import from_si


class StoreyYield(Effect):
    name = "storey_yield"
    physics = ("storeys of the specimen yield: a Bouc–Wen storey force (yield drift u_y, "
               "post-yield stiffness ratio α, sharpness n) on a storey, or on adjacent "
               "storeys alike")
    section = "ch. 3, §5.3 (amplitude-dependent fixed-base parameters; loops)"
    signature = ("the structure's response softens and damps more at large spans than at "
                 "small ones; storey shear flattens at a yield level; residual drift")
    params = (Param("storey", "1", 1.0, 1.0, 50.0, source="a choice: every storey is tried",
                    doc="the (lowest) storey that yields, 1-based from the bottom",
                    discrete=True),
              Param("storeys", "1", 1.0, 1.0, 50.0, source="a choice: the best storey's run "
                    "grown while it fits better", doc="how many adjacent storeys yield, from "
                    "`storey` up", discrete=True),
              Param("yield_drift", "in", 0.5, 0.01, 20.0, log=True,
                    source="assumed (a drift ratio of a few tenths of a %)",
                    doc="u_y, the drift at which it yields"),
              Param("post_yield_ratio", "1", 0.1, 0.0, 1.0,
                    source="assumed", doc="α, the post-yield stiffness over the elastic one"),
              Param("sharpness", "1", 2.0, 1.0, 10.0, log=True,
                    source="Wen 1976's usual shape (n = 2)",
                    doc="n, how sharp the transition to yield is: 2 a rounded knee, 8 or "
                        "more nearly elastic-perfectly-plastic (up to 10: RK4 at the "
                        "model's 2.5 ms step holds z for drift rates below ~1100/n "
                        "yield drifts per second)"))

    def apply(self, m, p):
        n = len(storey_masses(m.specimen))
        k, j = round(p["storey"]), round(p["storeys"])
        if not 1 <= k <= k + j - 1 <= n:
            which = f"storey {k}" if j == 1 else f"storeys {k}-{k + j - 1}"
            raise VtableError(f"storey_yield: {which}, but the specimen has "
                              f"{n or 'no'} storey{'s' if n != 1 else ''}")
        declared = getattr(m.specimen, "hysteresis", None)
        for i in range(k, k + j):
            if declared is not None and i in declared.storeys:
                raise VtableError(f"storey_yield: storey {i} is declared yielding already "
                                  "([specimen.hysteresis])")
            add_yielding_storey(m, m.specimen, i, p["yield_drift"], p["post_yield_ratio"],
                                p["sharpness"])

    def choices(self, specimen, tried=()):
        """Each storey of `specimen` alone first; then the best run tried so far grown by
        the storey below it and by the one above, while that lowers the training cost
        (n + 2 per storey the run grows, of the n (n + 1) / 2 runs there are: a tall
        building is not fitted once per run)."""
        n = len(storey_masses(specimen))
        if not tried:
            return [{"storey": k, "storeys": 1} for k in range(1, n + 1)]
        p, _ = min(tried, key=lambda t: t[1])
        k, j = round(p["storey"]), round(p["storeys"])
        return [{"storey": a, "storeys": b} for a, b in ((k - 1, j + 1), (k, j + 1))
                if a >= 1 and a + b - 1 <= n]

    def unseen(self, values, predictions):
        """A yield drift beyond every yielding storey's largest drift in the model's own
        prediction of every run (ductility below 1): no run shows them yield, and the fit
        has bought a smooth softening with an extrapolated u_y."""
        k, j = round(values["storey"]), round(values.get("storeys", 1))
        peaks = [float(np.max(np.abs(ch[f"floor{i}_drift"]))) for ch in predictions.values()
                 for i in range(k, k + j) if f"floor{i}_drift" in ch]
        u_y = self.param("yield_drift").to_si(values["yield_drift"])
        if not peaks or max(peaks) >= u_y:
            return None
        which = f"storey {k}'s" if j == 1 else f"storeys {k}-{k + j - 1}'s"
        return (f"storey_yield.yield_drift {values['yield_drift']:.3g} in is never reached "
                f"({which} largest drift in the model's prediction is "
                f"{from_si(max(peaks), 'in'):.3g} in): no run shows it yield")


EFFECT = StoreyYield()
