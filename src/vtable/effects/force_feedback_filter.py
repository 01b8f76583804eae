"""force_feedback_filter: an RC high-pass filter on the ΔP (force) feedback (app. B,
eqs B.4-B.7): the horizontal loop feeds back the filtered pressure P_f,
Ṗ_f = -P_f/RC + Ṗ_L, instead of P_L — a feedback stage of the hydraulic element
(linear)."""

from __future__ import annotations

from vtable.effects.base import Effect, Param
from vtable.hydraulics.stage import Stage


def filtered(P, z, p):
    """The pressure fed back: the filter's state P_f."""
    return z[0]


def filter_rate(P, dP, z, p, dz):
    """Ṗ_f = -P_f/RC + Ṗ_L (eq B.4)."""
    dz[0] = dP - z[0] / p.rc


RC_FILTER = Stage("rc_filter", "feedback", filtered, ("rc",), states=1, state_units=("Pa",),
                  linear=True,
                  rate=filter_rate)


class ForceFeedbackFilter(Effect):
    name = "force_feedback_filter"
    physics = "an RC high-pass filter on the ΔP (force) feedback"
    section = "app. B (eqs B.4-B.7)"
    signature = ("low-frequency phase and amplitude of x_t/x_c; the loop's damping seems lower "
                 "than the ΔP knob suggests")
    params = (Param("rc", "s", lambda t: t.rc, 1e-3, 1.0, log=True,
                    source="the table's RC (EERC: Table B.5)"),)

    def apply(self, m, p):
        m.add_stage(RC_FILTER, rc=p["rc"])


EFFECT = ForceFeedbackFilter()
