"""force_feedback_filter: an RC high-pass filter on the ΔP (force) feedback (app. B,
eqs B.4-B.7): the horizontal loop feeds back the filtered pressure P_f,
Ṗ_f = -P_f/RC + Ṗ_L, instead of P_L — a feedback stage of the hydraulic element
(linear; the law is `vtable.hydraulics.table_stages.RC_FILTER`, the EERC table's own)."""

from __future__ import annotations

from vtable.effects.base import Effect, Param
from vtable.hydraulics.table_stages import RC_FILTER


class ForceFeedbackFilter(Effect):
    name = "force_feedback_filter"
    physics = "an RC high-pass filter on the ΔP (force) feedback"
    section = "app. B (eqs B.4-B.7)"
    signature = ("low-frequency phase and amplitude of x_t/x_c; the loop's damping seems lower "
                 "than the ΔP knob suggests")
    params = (Param("rc", "s", lambda t: t.rc, 1e-3, 1.0, log=True,
                    source="the table's RC (EERC: Table B.5)"),)
    stages = (RC_FILTER,)

    def apply(self, m, p):
        m.add_stage(RC_FILTER, rc=p["rc"])


EFFECT = ForceFeedbackFilter()
