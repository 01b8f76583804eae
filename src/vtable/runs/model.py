"""A run in memory: time, channels in SI, what the TOML said, and what was reported."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vtable.errors import VtableError

_FLOOR = re.compile(r"floor([1-9][0-9]*)_(acc|disp)")


class _FormatUnits(dict):
    """The format's channel -> unit table. Besides the fixed names it holds the floor
    channels floorK_acc (g) and floorK_disp (in) for any K >= 1 (they are not listed
    when iterating)."""

    def __missing__(self, key: str) -> str:
        m = _FLOOR.fullmatch(key) if isinstance(key, str) else None
        if m is None:
            raise KeyError(key)
        return "g" if m.group(2) == "acc" else "in"

    def __contains__(self, key: object) -> bool:
        return dict.__contains__(self, key) or (
            isinstance(key, str) and _FLOOR.fullmatch(key) is not None)

    def get(self, key: str, default: Any = None) -> Any:
        return self[key] if key in self else default


#: the interchange format's channels and units (docs/run-format.md)
FORMAT_UNITS: dict[str, str] = _FormatUnits({
    "h_span": "in", "avg_hdisp": "in", "avg_vdisp": "in", "avg_hacc": "g", "avg_vacc": "g",
    "pitch_acc": "rad/s2", "roll_acc": "rad/s2", "twist_acc": "rad/s2", "pitch_disp": "rad",
    **{f"v{i}_disp": "in" for i in range(1, 5)}, **{f"h{i}_disp": "in" for i in range(1, 4)},
    **{f"h{i}_force": "kip" for i in range(1, 4)}, **{f"v{i}_force": "kip" for i in range(1, 5)},
    **{f"p{i}_stab": "kip" for i in range(1, 5)}, "h_vel": "in/s",
    "acc_n_ne": "g", "acc_n_nw": "g", "acc_w_nw": "g", "acc_w_sw": "g",
    "pot_n_sw": "in", "pot_n_se": "in", "acc_cmd": "g",
})
TOP_KEYS = ("format", "title", "table", "control", "specimen", "command", "units")
#: channels the controller generates: constant, they drive nothing
COMMAND_CHANNELS = ("h_span", "acc_cmd")


def channel_dimension(name: str) -> str | None:
    """The dimension of a format channel (length, acceleration, force, angle, ...); None
    for a channel the format does not name (an extra channel takes any unit)."""
    from vtable import units

    unit = FORMAT_UNITS.get(name)
    return None if unit is None else units.dimension(unit)


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
        """The [specimen] (a bare table when the run has none; the reader reports that)."""
        from vtable.params.specimen import NoSpecimen, specimen_from_dict

        if "specimen" not in self.meta:
            return NoSpecimen()
        return specimen_from_dict(self.meta["specimen"], f"{self.name} [specimen]")

    def table(self):
        """The [table] description (`vtable.runs.table.TableDescription`), None when the
        run has no [table]."""
        from vtable.runs.table import table_from_dict

        if "table" not in self.meta:
            return None
        return table_from_dict(self.meta["table"], f"{self.name} [table]")

    def drive(self):
        """The [command] description (`vtable.runs.format.CommandDescription`: kind, band,
        drive file, ...), None when the run has no [command]. The drive file itself is not
        read yet."""
        from vtable.runs.format import command_from_dict

        if "command" not in self.meta:
            return None
        folder = self.source.parent if self.source is not None else None
        return command_from_dict(self.meta["command"], f"{self.name} [command]", folder)

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
