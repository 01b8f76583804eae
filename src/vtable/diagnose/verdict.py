"""What a diagnosis concludes, in words and in its result: the verdict (what was added,
whether the final error is within the noise, where a residual lives and what no model of
the command can fit, the declarations the model leans on, why the search stopped) and the
`Diagnosis` that carries it with the rounds, stages and comparisons."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from vtable.diagnose.bounds import base_at_bounds, bounds_verdict
from vtable.diagnose.command_check import command_checks
from vtable.diagnose.findings import findings, headline
from vtable.diagnose.limits import limits
from vtable.diagnose.noise import NOISE_FACTOR, within_noise
from vtable.diagnose.plants import plant_differences
from vtable.diagnose.prose import unexplained
from vtable.diagnose.reading import force_stage
from vtable.diagnose.result import READING_STEP, Diagnosis, DiagnosisStage, Round
from vtable.diagnose.states import state_rows
from vtable.diagnose.stationarity import stationarity_check
from vtable.diagnose.statistics import Comparison
from vtable.models.physics import Physics


@dataclass
class State:
    """What the loop has established so far (read by the caller on an interrupt)."""

    current: Physics | None = None
    err: float | None = None
    start_err: float | None = None
    cmp0: Comparison | None = None
    cmp: Comparison | None = None  # detailed comparison of `current`, when made
    rounds: list[Round] = field(default_factory=list)
    stages: list[DiagnosisStage] = field(default_factory=list)
    result: Diagnosis | None = None
    error: BaseException | None = None
    #: declarations the final model leans on that a widened refit moves beyond their
    #: bounds (`bounds.pushed_beyond`)
    pushed: list[dict[str, Any]] = field(default_factory=list)
    #: pairs of runs that did not hold one plant the model described (`states.split`),
    #: and whether the campaign was then fitted with a specimen state per run
    plants: list | None = None
    split: bool = False
    #: (predictions, the pairs of runs they leave differing as plants): worked out once
    #: for a stage's predictions (`states.differences`)
    plant_pairs: tuple | None = None
    #: the force channels' other reading, tried once (`reading.force_reading`); None: not
    reading: dict[str, Any] | None = None

    def adopt(self, name: str, physics: Physics, err: float, predictions) -> None:
        """`physics` (held-out error `err`, its `predictions`) becomes the current model,
        the stage `name` (numbered); its detailed comparison is made when asked."""
        self.current, self.err, self.cmp = physics, err, None
        self.stages.append(DiagnosisStage(f"{len(self.stages)}_{name}", physics, predictions))



def diagnosis_of(d, st: State, final_cmp: Comparison | None, reason: str,
                 interrupted: bool = False, said=lambda s: None) -> Diagnosis:
    """The `Diagnosis` of diagnoser `d`'s loop state `st` (a `Diagnoser`), its final
    comparison `final_cmp` (None: not made, an interrupted loop) and why it stopped;
    `said` hears the checks it runs (`command_check.command_checks`)."""
    current = st.current or d.start
    err = st.err
    added = [r.added for r in st.rounds if r.added]
    floor = d.floor
    unexp = None
    if final_cmp is not None:
        unexp = unexplained(final_cmp)
    elif err is not None and not within_noise(err, floor):
        unexp = {"ratio_to_floor": err / floor if floor > 0 else float("inf"),
                 "where": "not localised (the diagnosis was interrupted)"}
    parts = []
    if interrupted:
        parts.append(f"interrupted after round {len(st.rounds)}"
                     + ("" if err is not None else ", before the starting model was fitted")
                     + "; the diagnosis is incomplete")
    removed = [e for r in st.rounds for e in r.removed]
    if added:
        parts.append(f"added {', '.join(added)}"
                     + (f" (later removed: {', '.join(removed)})" if removed else "")
                     + f": held-out error {st.start_err:.2%} -> {err:.2%} (noise floor "
                       f"{floor:.2%})")
    if err is not None:
        if unexp is None:
            lead = "no missing effect" if not added else "no further missing effect"
            if interrupted:
                lead = "so far within the noise"
            parts.append(f"{lead}: the final held-out error {err:.2%} is within "
                         f"{NOISE_FACTOR:g} x the noise floor ({floor:.2%})")
        else:
            parts.append(f"a residual remains unexplained: the final held-out error "
                         f"{err:.2%} is {unexp['ratio_to_floor']:.1f} x the noise floor "
                         f"({floor:.2%}), above the {NOISE_FACTOR:g} x noise alone explains;"
                         f" it lives in {unexp['where']}")
            for c in d.campaign.sensors:  # what no effect on the platen can fit
                parts.append(c.text())
            if st.stages:  # what no time-invariant model of the command can fit
                preds = st.stages[-1].predictions
                for r in d.runs:
                    c = stationarity_check(r, preds.get(r.name))
                    text = "" if c is None else c.text(floor, NOISE_FACTOR)
                    if text:
                        parts.append(text)
    base = d.base_table(current)
    start = getattr(d, "start_fitted", None)
    at_bounds = [] if err is None else base_at_bounds(
        base, d.calibration, None if start is None else d.base_table(start),
        st.pushed)
    if at_bounds:  # deliverable 6 of issue 18: the suspect declarations named
        parts.append(bounds_verdict(at_bounds, d.calibration))
    if reason:
        parts.append(reason)
    preds = st.stages[-1].predictions if st.stages and err is not None else None
    diag = Diagnosis(list(d.start.effects), st.start_err, floor, list(st.rounds),
                     current, err, "; ".join(parts), st.cmp0, final_cmp,
                     base, unexp, list(d.notes), interrupted,
                     list(st.stages), list(d.runs), base_at_bounds=at_bounds,
                     limits=None if preds is None else limits(d.runs, preds))
    lim = diag.limits
    # a bound only where a split was resolved (elsewhere it is the noise standing in)
    resolved = lim is not None and any(g.resolved for g in lim.groups)
    diag.states = state_rows(base, d.campaign.states)
    diag.states_declared = bool(diag.states) and not st.split
    diag.force_reading = st.reading
    if diag.reading_kept and not force_stage(current, d.vt):  # friction removed later:
        st.reading.update(found=st.reading["assumed"],  # the two readings agree
                          why_not="the final model holds no force stage (the readings agree)")
        diag.final = dataclasses.replace(current, force_measured=None)
    diag.headline = headline(added + (["a specimen state per run"] if st.split else [])
                             + ([READING_STEP.format(st.reading["found"])] if diag.reading_kept
                                else []),
                             st.start_err, err, floor,
                             lim.bound if resolved else None,
                             None if lim is None else lim.reference, interrupted)
    plants = st.plants if st.plants is not None else (
        [] if preds is None else plant_differences(d.runs, preds))
    diag.findings = findings(diag, d.campaign.sensors, d.campaign.notches, plants,
                             getattr(d.table_view, "evidence", None),
                             command_checks(d, diag, said))
    return diag
