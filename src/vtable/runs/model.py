"""A run in memory: time, channels in SI, what the TOML said, and what was reported."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vtable.errors import VtableError

#: the interchange format's channels and units (shared/spec/measurement-format.md)
FORMAT_UNITS: dict[str, str] = {
    "h_span": "in", "avg_hdisp": "in", "avg_vdisp": "in", "avg_hacc": "g", "avg_vacc": "g",
    "pitch_acc": "rad/s2", "roll_acc": "rad/s2", "twist_acc": "rad/s2", "pitch_disp": "rad",
    **{f"v{i}_disp": "in" for i in range(1, 5)}, **{f"h{i}_disp": "in" for i in range(1, 4)},
    **{f"h{i}_force": "kip" for i in range(1, 4)}, **{f"v{i}_force": "kip" for i in range(1, 5)},
    **{f"p{i}_stab": "kip" for i in range(1, 5)}, "h_vel": "in/s",
    "acc_n_ne": "g", "acc_n_nw": "g", "acc_w_nw": "g", "acc_w_sw": "g",
    "pot_n_sw": "in", "pot_n_se": "in", "acc_cmd": "g",
}
TOP_KEYS = ("format", "title", "table", "control", "specimen", "command", "units")


@dataclass
class Run:
    """One run. `channels` are in SI; `units` the unit each channel has in its file."""

    name: str
    time: np.ndarray
    channels: dict[str, np.ndarray]
    units: dict[str, str]
    meta: dict[str, Any]
    source: Path | None = None
    missing: dict[str, int] = field(default_factory=dict)
    extra: list[str] = field(default_factory=list)
    reports: list[str] = field(default_factory=list)

    @property
    def dt(self) -> float:
        return float((self.time[-1] - self.time[0]) / (len(self.time) - 1))

    @property
    def fs(self) -> float:
        return 1.0 / self.dt

    @property
    def duration(self) -> float:
        return float(self.time[-1] - self.time[0])

    def has(self, name: str) -> bool:
        return name in self.channels

    def channel(self, name: str) -> np.ndarray:
        """A channel in SI; absent or with missing samples is a one-line error."""
        if name not in self.channels:
            raise VtableError(f"{self.name}: no channel {name!r} (it has "
                              f"{', '.join(sorted(self.channels)) or 'none'})")
        if self.missing.get(name):
            raise VtableError(f"{self.name}: channel {name!r} has {self.missing[name]} missing "
                              "samples; vtable does not fill them in")
        return self.channels[name]

    def specimen(self):
        from vtable.params.specimen import specimen_from_dict

        if "specimen" not in self.meta:
            raise VtableError(f"{self.name}: no [specimen] table")
        return specimen_from_dict(self.meta["specimen"], f"{self.name} [specimen]")

    def configuration(self) -> dict[str, Any]:
        """What must agree across a campaign: table, control settings, specimen."""
        return {k: self.meta.get(k) for k in ("table", "control", "specimen")}


def with_noise(run: Run, fraction: float, seed: int = 0,
               exclude: tuple[str, ...] = ("h_span", "acc_cmd")) -> Run:
    """A copy with white Gaussian sensor noise of `fraction` x each channel's RMS (the
    command channels, which the controller generates, are left clean)."""
    import dataclasses

    rng = np.random.default_rng(seed)
    noisy = {}
    for k, v in run.channels.items():
        if k in exclude or k.startswith("state_"):
            noisy[k] = v.copy()
            continue
        rms = float(np.sqrt(np.nanmean(v**2)))
        noisy[k] = v + fraction * rms * rng.standard_normal(len(v))
    return dataclasses.replace(run, channels=noisy,
                               reports=[*run.reports, f"{fraction:.1%} RMS sensor noise added"])
