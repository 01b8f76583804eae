"""pitch_flexibility: the table rocks about y.

The platen pitches against the vertical actuators' pitch control loop and the passive
stabilizers (report ch. 5, 8): together a rocking spring k_θ and dashpot c_θ at the
coupled frequency (the hybrid model, eq 8.37; Table 8.1). In both models the pitch DOF is
freed and the stabilizers are retuned so that, with the vertical actuators' loop, the
rocking impedance at the §8.6.3 coupled frequency is (k_θ, c_θ) (`split_rocking`,
eqs 8.32-8.33, 8.4).
"""

from __future__ import annotations

from vtable import units
from vtable.effects.base import Effect, Param
from vtable.params import presets


class PitchFlexibility(Effect):
    name = "pitch_flexibility"
    physics = ("the table rocks about y against the vertical actuators' control loop and the "
               "passive stabilizers: a rocking spring k_θ and dashpot c_θ (hybrid model, "
               "eq 8.37)")
    section = "ch. 5, 8"
    signature = ("pitch channels driven at the coupled frequency; the x_t/x_c peak and notch "
                 "move below the fixed-base frequency; structure response near f_c")
    params = (Param("k_theta", "lb-in/rad", lambda: _rocking("k_theta", "lb-in/rad"), 1e9, 1e12,
                    log=True, source="Table 8.1"),
              Param("c_theta", "lb-in-s/rad", lambda: _rocking("c_theta", "lb-in-s/rad"), 1e6,
                    1e10, log=True, source="Table 8.1"))

    def apply(self, m, p):
        m.unlock("pitch")
        m.set_rocking(p["k_theta"], p["c_theta"])


def _rocking(attr: str, unit: str) -> float:
    return float(units.from_si(getattr(presets.hybrid_rocking(), attr), unit))


EFFECT = PitchFlexibility()
