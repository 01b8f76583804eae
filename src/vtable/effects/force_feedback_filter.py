"""force_feedback_filter: an RC high-pass filter on the ΔP (force) feedback (app. B,
eqs B.4-B.7): the horizontal loop feeds back the filtered pressure P_f,
Ṗ_f = -P_f/RC + Ṗ_L, instead of P_L."""

from __future__ import annotations

from vtable.effects.base import Effect, Param
from vtable.params import presets


class ForceFeedbackFilter(Effect):
    name = "force_feedback_filter"
    physics = "an RC high-pass filter on the ΔP (force) feedback"
    section = "app. B (eqs B.4-B.7)"
    signature = ("low-frequency phase and amplitude of x_t/x_c; the loop's damping seems lower "
                 "than the ΔP knob suggests")
    params = (Param("rc", "s", lambda: presets.eerc_table().servo.rc, 1e-3, 1.0, log=True,
                    source="Table B.5"),)

    def apply(self, m, p):
        m.set_servo(rc=p["rc"])


EFFECT = ForceFeedbackFilter()
