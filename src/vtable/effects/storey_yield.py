"""storey_yield: a storey of the specimen yields — the Bouc–Wen storey of
`vtable.analytic.hysteresis` (Wen 1976; Baber & Wen 1981) on storey `storey`, with its yield
drift u_y and post-yield stiffness ratio α fitted (n = 2, β = γ = 0.5, the usual shape).

A default candidate of `diagnose` like every catalog effect: it is fitted only where the
runs show amplitude dependence the current model misses (`vtable.diagnose.screen`). The
storey is a choice, not a distance: the fit tries every storey the specimen has and keeps
the best (`Param(discrete=True)`). A bare table or a rigid block has no storey, and
the effect cannot be built there. The report treats the fixed-base parameters as
amplitude-dependent (ch. 3, §5.3's loops); this is that dependence as a yielding storey.
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
    physics = ("a storey of the specimen yields: a Bouc–Wen storey force (yield drift u_y, "
               "post-yield stiffness ratio α) on that storey")
    section = "ch. 3, §5.3 (amplitude-dependent fixed-base parameters; loops)"
    signature = ("the structure's response softens and damps more at large spans than at "
                 "small ones; storey shear flattens at a yield level; residual drift")
    params = (Param("storey", "1", 1.0, 1.0, 50.0, source="a choice: every storey is tried",
                    doc="the storey that yields, 1-based from the bottom", discrete=True),
              Param("yield_drift", "in", 0.5, 0.01, 20.0, log=True,
                    source="assumed (a drift ratio of a few tenths of a %)",
                    doc="u_y, the drift at which it yields"),
              Param("post_yield_ratio", "1", 0.1, 0.0, 1.0,
                    source="assumed", doc="α, the post-yield stiffness over the elastic one"))

    def apply(self, m, p):
        n = len(storey_masses(m.specimen))
        k = round(p["storey"])
        if not 1 <= k <= n:
            raise VtableError(f"storey_yield: storey {k}, but the specimen has "
                              f"{n or 'no'} storey{'s' if n != 1 else ''}")
        declared = getattr(m.specimen, "hysteresis", None)
        if declared is not None and k in declared.storeys:
            raise VtableError(f"storey_yield: storey {k} is declared yielding already "
                              "([specimen.hysteresis])")
        add_yielding_storey(m, m.specimen, k, p["yield_drift"], p["post_yield_ratio"])

    def unseen(self, values, predictions):
        """A yield drift beyond the storey's largest drift in the model's own prediction
        of every run (ductility below 1): no run shows the storey yield, and the fit has
        bought a smooth softening with an extrapolated u_y."""
        k = round(values["storey"])
        peaks = [float(np.max(np.abs(ch[f"floor{k}_drift"]))) for ch in predictions.values()
                 if f"floor{k}_drift" in ch]
        u_y = self.param("yield_drift").to_si(values["yield_drift"])
        if not peaks or max(peaks) >= u_y:
            return None
        return (f"storey_yield.yield_drift {values['yield_drift']:.3g} in is never reached "
                f"(storey {k}'s largest drift in the model's prediction is "
                f"{from_si(max(peaks), 'in'):.3g} in): no run shows it yield")


EFFECT = StoreyYield()
