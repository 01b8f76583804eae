"""A campaign prepared for fitting and scoring: its runs checked and at their analysis rate
(`compare.analysis_run`), what the readers reported, the noise floor, and the training
targets (every channel group of every run, training segment, every other sample)."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vtable.diagnose.compare import (
    NOISE_FACTOR,
    analysis_run,
    campaign_notes,
    group_noise,
    group_signal,
    noise_floor,
    run_groups,
    segments,
)
from vtable.diagnose.sampling import SCREEN_SHARE
from vtable.diagnose.sensors import sensor_check
from vtable.diagnose.stationarity import stationarity_check
from vtable.effects.registry import get as effect
from vtable.errors import VtableError
from vtable.runs.lab import run_table
from vtable.runs.model import Run
from vtable.runs.read import check_configuration

REQUIRED = ("h_span",)


def check_campaign(runs: Sequence[Run]) -> list[Run]:
    """Clear messages for what a diagnosis cannot use; returns the runs at their analysis
    rate (`compare.analysis_run`)."""
    if not runs:
        raise VtableError("diagnosis needs at least one run")
    for r in runs:
        if "specimen" not in r.meta:
            raise VtableError(f"{r.name}: no [specimen] table; the model needs the specimen")
    check_configuration(list(runs))
    out = []
    for r in runs:
        for c in REQUIRED:
            if not r.has(c):
                raise VtableError(f"{r.name}: channel {c!r} (the command) is missing; the "
                                  "model is driven by it")
            if r.missing.get(c):
                raise VtableError(f"{r.name}: channel {c!r} has {r.missing[c]} missing samples")
        x = r.channels["h_span"]
        if not np.all(np.isfinite(x)):
            raise VtableError(f"{r.name}: channel 'h_span' has non-finite samples")
        if np.ptp(x) == 0:
            raise VtableError(f"{r.name}: channel 'h_span' (the command) is "
                              + ("zero throughout" if not np.any(x) else f"constant ({x[0]:g} m)")
                              + "; a model driven by it predicts no motion to compare")
        a = analysis_run(r)
        if len(a.time) < 512:
            raise VtableError(f"{r.name}: {len(a.time)} samples ({r.duration:.2f} s) at "
                              f"{a.fs:.4g} Hz is shorter than one 512-sample analysis frame")
        if not any(group_signal(a, g) is not None for g in run_groups(a) if g != "pitch"):
            raise VtableError(f"{r.name}: none of the response channels the model predicts "
                              f"({', '.join(c for g in run_groups(a).values() for c in g)})")
        out.append(a)
    return out


def _targets(runs: Sequence[Run], whole: bool, share: float = 1.0
             ) -> list[tuple[Run, str, np.ndarray, float]]:
    """(run, group, training samples (every other one), their norm) of every group of
    every run (`segments`, `whole` or not, the first `share` of it)."""
    out = []
    for r in runs:
        tr, _ = segments(r, whole, share)
        for g in run_groups(r):
            y = group_signal(r, g)
            if y is not None:
                yt = y[tr][::2]
                out.append((r, g, yt, float(np.linalg.norm(yt))))
    return out


#: the noise floor of a campaign whose sensors are quieter (noise-free runs): the verdict
#: judges the final error against at least this. The selection does not use it: it takes
#: the resolution of each model it compares from the effects in it, measured
#: (`vtable.diagnose.resolution`: 0.33 % for the base, 0.28-0.63 % with one catalog effect)
MODEL_RESOLUTION = 0.005
#: the state of the runs that declare none in a campaign where others do
UNDECLARED = "(undeclared)"


@dataclass
class Campaign:
    """`source_runs` as read; `runs` at the analysis rate; `targets` (run, group, training
    samples, their norm) for the least-squares fits."""

    source_runs: list[Run]
    runs: list[Run]
    notes: list[str]
    floor: float
    targets: list[tuple[Run, str, np.ndarray, float]] = field(repr=False)
    #: runs whose table acceleration and displacement disagree (`sensors.sensor_check`)
    sensors: list = field(default_factory=list)
    #: run -> (first Hz, last Hz, window s) of an x_t/x_c notch that moves within the run
    #: (`stationarity.stationarity_check`)
    notches: dict = field(default_factory=dict)
    #: run -> the specimen's state it was made in ([specimen] state, or a state per run
    #: the diagnosis gives runs that do not hold one plant: `with_states`); empty: one
    state_of: dict = field(default_factory=dict)
    #: set by a diagnosis when its time-invariant rounds are done and their model leaves
    #: more than the noise explains in runs of one plant (`states.unexplained`): whether
    #: its residual changes within a run (`screen.ChangeEvidence`); None: not asked
    residual_change: Any = None

    #: the training targets span each run's whole first 60 % (`whole_training`), not only
    #: its first `TRAIN_MAX_S`
    whole: bool = False
    #: the share of each run's training segment the targets span: 1, or `SCREEN_SHARE`
    #: (`screening`)
    share: float = 1.0

    @classmethod
    def of(cls, runs: Sequence[Run] | Campaign) -> Campaign:
        if isinstance(runs, Campaign):
            return runs
        a = check_campaign(runs)
        targets = _targets(a, False)
        notes, floor = campaign_notes(a), noise_floor(a)
        sensors = [c for c in map(sensor_check, a) if c is not None and not c.agree]
        notes += [c.text() for c in sensors]
        notches = {}
        for c in map(stationarity_check, a):  # a notch that moves: the specimen changes
            if c is not None and c.notch is not None:
                notes.append(c.text(floor, NOISE_FACTOR))
                notches[c.run] = c.notch
        if floor < MODEL_RESOLUTION:
            notes.append(f"the runs' sensor noise ({floor:.2%} of the signals) is below what "
                         f"the reduced model resolves ({MODEL_RESOLUTION:.1%}, its agreement "
                         "with the multibody table); that is the noise floor used")
            floor = MODEL_RESOLUTION
        states = {r.name: r.state for r in a} if any(r.state for r in a) else {}
        return cls(list(runs), a, notes, floor, targets, sensors, notches,
                   {k: v or UNDECLARED for k, v in states.items()})

    def with_states(self, state_of: dict[str, str]) -> Campaign:
        """This campaign with the runs' states given (run name -> state)."""
        return dataclasses.replace(self, state_of=dict(state_of))

    def training_for(self, ph) -> Campaign:
        """The campaign a model `ph` (`Physics`) is fitted on: `whole_training` when one of
        its effects `accumulates`, else this one."""
        if any(effect(e).accumulates for e in ph.effects):
            return self.whole_training()
        return self

    def apart(self, a, b) -> bool:
        """Whether models `a` and `b` (`Physics`) are fitted on different training windows
        (`training_for`): their training costs do not compare."""
        return self.training_for(a) is not self.training_for(b)

    def whole_training(self) -> Campaign:
        """This campaign with training targets over each run's whole first 60 % (a model
        holding an effect that `accumulates`); kept, built once."""
        if self.whole:
            return self
        if "_whole" not in self.__dict__:
            self._whole = dataclasses.replace(self, targets=_targets(self.runs, True,
                                                                     self.share), whole=True)
        return self._whole

    def screening(self) -> Campaign:
        """This campaign with training targets over the first `SCREEN_SHARE` of each run's
        training segment (a candidate's screen, `vtable.diagnose.projected`); kept, built
        once."""
        if self.share != 1.0:
            return self
        if "_screening" not in self.__dict__:
            self._screening = dataclasses.replace(
                self, targets=_targets(self.runs, self.whole, SCREEN_SHARE),
                share=SCREEN_SHARE)
        return self._screening

    def train_stop(self, run: Run) -> int:
        """The samples of `run` a fit on this campaign simulates (its training segment's
        end: `segments`)."""
        return segments(run, self.whole, self.share)[0].stop

    @property
    def states(self) -> dict[str, list[str]]:
        """Each state -> its runs, in the order of first appearance (the first is the base
        state: the model's `specimen`; empty when the campaign has one)."""
        out: dict[str, list[str]] = {}
        for r in self.runs:
            if r.name in self.state_of:
                out.setdefault(self.state_of[r.name], []).append(r.name)
        return out if len(out) > 1 else {}

    def state(self, run: Run | str) -> str | None:
        """The specimen's state of `run` (its name: `state_of`, else what the run itself
        declares), None when neither says."""
        name = run if isinstance(run, str) else run.name
        if name in self.state_of:
            return self.state_of[name]
        return None if isinstance(run, str) else run.state

    @property
    def state_specimens(self) -> dict:
        """Each state beyond the first -> the specimen its first run declares."""
        by_name = {r.name: r for r in self.runs}
        return {s: by_name[names[0]].specimen() for s, names in list(self.states.items())[1:]}

    @property
    def noise(self) -> dict[str, dict[str, float]]:
        """Each run's channel groups' sensor noise σ per sample (`compare.group_noise`)."""
        if not hasattr(self, "_noise"):
            self._noise = {r.name: group_noise(r) for r in self.runs}
        return self._noise

    @property
    def specimen(self):
        return self.runs[0].specimen()

    @property
    def table(self):
        """The runs' table as the models read it (`vtable.params.virtual.VirtualTable`)."""
        if not hasattr(self, "_vt"):
            self._vt = run_table(self.runs[0])
        return self._vt

    @property
    def target_channels(self) -> list[tuple[Run, list[str]]]:
        """Each run with the channels its training targets' groups average (`targets`)."""
        if not hasattr(self, "_target_channels"):
            out: dict[str, tuple[Run, list[str]]] = {}
            for r, g, *_ in self.targets:
                names = out.setdefault(r.name, (r, []))[1]
                names += [c for c in run_groups(r).get(g, ())
                          if r.has(c) and not r.missing.get(c) and c not in names]
            self._target_channels = list(out.values())
        return self._target_channels

    @property
    def target_groups(self) -> list[list[str]]:
        """Each target's channels (`targets`): the model's prediction of the group is their
        mean (`groups.group_prediction`)."""
        if not hasattr(self, "_target_groups"):
            self._target_groups = [[c for c in run_groups(r).get(g, ())
                                    if r.has(c) and not r.missing.get(c)]
                                   for r, g, *_ in self.targets]
        return self._target_groups

    @property
    def target_vectors(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The training targets end to end: (the measured samples, 1/norm of each sample's
        target, the residual a non-finite prediction gets: 10/√n of its target)."""
        if not hasattr(self, "_target_vectors"):
            self._target_vectors = (
                np.concatenate([y for _, _, y, _ in self.targets]),
                np.concatenate([np.full(len(y), 1.0 / norm) for _, _, y, norm in self.targets]),
                np.concatenate([np.full(len(y), 10.0 / np.sqrt(len(y)))
                                for _, _, y, _ in self.targets]))
        return self._target_vectors

    @property
    def n_target(self) -> int:
        return sum(len(t[2]) for t in self.targets)
