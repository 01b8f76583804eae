"""The calibrated model a drive is played on (`DrivePlant`): the fitted `TableModel`'s
reduced model in the specimen state the runs left (`driven`), its channels under a drive
with x_t, x_eff = x_t + θh and the storey drift added, and the H1 a lab's white-noise run
would give of it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.signal

from vtable.diagnose.model import TableModel
from vtable.ident.tf import transfer_function
from vtable.models.reduced import ReducedModel
from vtable.signals import band_limited_random

#: the band the inverse acts in (Hz); above it the drive is the target's
BAND_HZ = (0.0, 30.0)


def driven(model: TableModel):
    """(the model's physics a drive is played on, its specimen state or None): of a model
    fitted on several specimen states, the state of the campaign's last run (the specimen
    as the runs left it)."""
    camp = getattr(model, "campaign_", None)
    if camp is None or not model.physics_.states:
        return model.physics_, None
    state = camp.state(camp.runs[-1])
    return model.physics_.in_state(state), state


@dataclass
class DrivePlant:
    """The calibrated model a drive is played on: the fitted `TableModel`'s reduced model
    and the effective height h of x_eff = x_t + θh."""

    model: TableModel
    h: float

    def __post_init__(self) -> None:
        self.physics, self.state = driven(self.model)
        self.reduced = ReducedModel(self.physics, self.model.vt)

    def play(self, t: np.ndarray, d: np.ndarray) -> dict[str, np.ndarray]:
        """The model's channels (SI) under drive `d`, with x_t, x_eff and the storey
        drift (top relative to the effective base) added."""
        out = dict(self.reduced.simulate(t, d))
        th = out.get("pitch_disp", np.zeros_like(d))
        out["x_t"] = out["avg_hdisp"]
        out["x_eff"] = out["avg_hdisp"] + self.h * th
        out["a_t"] = out["avg_hacc"]
        out["a_eff"] = out["avg_hacc"] + self.h * out.get("pitch_acc", np.zeros_like(d))
        if "pot_n_sw" in out:
            out["drift"] = out["pot_n_sw"] - out["avg_hdisp"] - self.reduced.h_top * th
        return out

    def frequency_response(self, output: str, fs: float, peak: float,
                           seconds: float = 60.0, seed: int = 0
                           ) -> tuple[np.ndarray, np.ndarray]:
        """H1 from the drive to `output` (a `play` channel: x_eff, x_t, drift) over a
        random drive of `peak` (m), flat over 0-30 Hz (`vtable.signals.
        band_limited_random`), played on the model: what a lab's white-noise run gives."""
        t, d = band_limited_random(seconds - 1 / fs, 1 / fs, BAND_HZ, peak=peak, seed=seed)
        d = d * scipy.signal.windows.tukey(len(d), 0.05)
        y = self.play(t, d)[output]
        tf = transfer_function(d, y, fs, 2048 if len(d) >= 8 * 1024 else 512)
        return tf.f, tf.H
