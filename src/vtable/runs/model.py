"""A run in memory: time, channels in SI, what the TOML declared (parsed once), and what
was reported."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vtable.errors import VtableError
from vtable.params.specimen import NoSpecimen, Specimen
from vtable.runs.channels import COMMAND_CHANNELS, FORMAT_UNITS, channel_dimension
from vtable.runs.format import CommandDescription
from vtable.runs.meta import Declaration, declare
from vtable.runs.table import TableDescription

__all__ = ["COMMAND_CHANNELS", "FORMAT_UNITS", "Declaration", "Run", "channel_dimension",
           "with_noise"]


@dataclass
class Run:
    """One run. `channels` are in SI; `units` the unit each channel has in its file;
    `meta` the TOML as read and `declared` the same parsed into typed fields (SI).

    The reader parses the TOML once and passes `declared`; a run made in code (or
    `dataclasses.replace` with a new `meta`) has it parsed on construction. Change `meta`
    with `dataclasses.replace`, not in place: `declared` is not parsed again otherwise."""

    name: str
    time: np.ndarray
    channels: dict[str, np.ndarray]
    units: dict[str, str]
    meta: dict[str, Any]
    source: Path | None = None
    missing: dict[str, int] = field(default_factory=dict)
    extra: list[str] = field(default_factory=list)
    reports: list[str] = field(default_factory=list)
    declared: Declaration | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.declared is None or self.declared.meta is not self.meta:
            folder = self.source.parent if self.source is not None else None
            self.declared = declare(self.meta, self.name, folder)

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

    def specimen(self) -> Specimen:
        """The [specimen] (a bare table when the run has none; the reader reports that)."""
        return self.declared.specimen or NoSpecimen()

    def table(self) -> TableDescription | None:
        """The [table] description, None when the run has no [table]."""
        return self.declared.table

    def drive(self) -> CommandDescription | None:
        """The [command] description (kind, band, drive file, ...), None when the run has
        no [command]."""
        return self.declared.command

    @property
    def state(self) -> str | None:
        """The specimen's state the run declares ([specimen] state), or None."""
        return None if self.declared is None else self.declared.state

    def configuration(self) -> dict[str, Any]:
        """What must agree across a campaign: table, control settings, specimen (its
        `state` apart: `vtable.runs.read.check_configuration` compares the specimens)."""
        out = {k: self.meta.get(k) for k in ("table", "control", "specimen")}
        if isinstance(out["specimen"], dict):
            out["specimen"] = {k: v for k, v in out["specimen"].items() if k != "state"}
        return out


def with_noise(run: Run, fraction: float, seed: int = 0,
               exclude: tuple[str, ...] = COMMAND_CHANNELS) -> Run:
    """A copy with white Gaussian sensor noise of `fraction` x each channel's RMS (the
    command channels, which the controller generates, are left clean)."""
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
