"""What a diagnosis and a comparison return (python-control's `*_response` pattern): typed
results with `to_json()` (the JSON the command line writes: the diagnosis's keys are the
interchange contract of docs/diagnosis-json.md), `report()` (the text it prints) and, for a
diagnosis, `plot()` (the HTML report and the Rerun recording, `vtable.viz`).

A diagnosis keeps its stages (`DiagnosisStage`: each model it went through, with its predictions and
comparison), its rounds (`Round`: the ranking of `Candidate`s, what was added and removed)
and the verdict; `DiagnosisInterrupted` carries the rounds finished on Ctrl-C.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vtable.diagnose.limits import Limits, limits
from vtable.diagnose.model import SCREEN, TableModel
from vtable.diagnose.noise import UNEXPLAINED_RULE
from vtable.diagnose.prose import (
    base_lines,
    linear_model,
    localisation_text,
    params_text,
    unexplained,
)
from vtable.diagnose.selection import SELECTION, failing
from vtable.diagnose.statistics import Comparison, Gain
from vtable.jsonable import jsonable
from vtable.models.physics import Physics
from vtable.runs.model import Run

ERROR_DEFINITION = ("mean over runs and channel groups of the normalised RMS error "
                    "||model - measured|| / ||measured|| on the held-out last 40 % of every "
                    "run, at the analysis rate (runs faster than 200 Hz anti-alias filtered and "
                    "resampled to 200 Hz); the noise floor is the same measure for the sensor "
                    "noise alone")



#: how the headline and the error history name a force reading kept (`force_reading`)
READING_STEP = "force read as {}"


@dataclass
class DiagnosisStage:
    """A model the diagnosis went through, with what it predicts for every run (analysis
    rate) and how that compares with the measurements: the report and the recording render
    these without simulating again."""

    label: str
    physics: Physics = field(repr=False)
    predictions: dict[str, dict[str, np.ndarray]] = field(repr=False)
    comparison: Comparison | None = None


@dataclass
class Candidate:
    effect: str
    params: dict[str, float]
    error_after: float
    train_error: float
    evidence: str
    n_params: int
    physics: Physics = field(repr=False)
    flags: list[str] = field(default_factory=list)
    predictions: dict | None = field(default=None, repr=False)
    screened: bool = False  # its first fit steps lowered the training cost < 1 %: stopped
    cost: float = float("nan")  # the fit's training cost (residuals and priors)
    gain: Gain | None = None  # its held-out gain over the current model (`SELECTION`)
    table: Any = field(default=None, repr=False)  # the campaign's `TableView` (its defaults)
    #: the SELECTION criteria its gain fails over the starting model refitted with its
    #: leaning bounds widened (empty: it beats a wrong declaration too, or none leaned)
    stand_in: list[str] = field(default_factory=list)
    #: why it was not fitted at all (`vtable.diagnose.screen`: a nonlinear candidate on
    #: runs that show no amplitude dependence); its prediction is the current model's
    not_fitted: str = ""
    #: why it passed the screen but was not refined (it cannot win the round: `engine`);
    #: its values and prediction are where the screen left it
    unrefined: str = ""

    @property
    def blocking(self) -> list[str]:
        """The flags on the candidate's own parameters (at a bound, not identifiable, no
        valid model): it is not added on that evidence. Flags on base parameters (a
        calibrated value at its bound) are reported but do not block: they say the model
        still lacks something, not that this effect is wrong."""
        return [f for f in self.flags if f.startswith((f"{self.effect}.", "no valid model"))]

    @property
    def score(self) -> float:
        """The ranking's key: the held-out mean squared NRMS error (`Gain.e2_candidate`)."""
        return self.gain.e2_candidate if self.gain is not None else float("inf")

    def failing(self) -> list[str]:
        """The statistical criteria of `SELECTION` this candidate's gain does not meet."""
        return failing(self.gain, self.physics, self.effect, self.table)



@dataclass
class Round:
    ranking: list[Candidate]
    added: str | None
    error: float
    before: float
    skipped: dict[str, str] = field(default_factory=dict)  # effect -> why it cannot apply
    #: effects added earlier and removed after this round's addition: effect -> why
    removed: dict[str, str] = field(default_factory=dict)


@dataclass
class Diagnosis:
    start_effects: list[str]
    start_error: float | None
    noise_floor: float
    rounds: list[Round]
    final: Physics
    final_error: float | None
    verdict: str
    comparison_start: Comparison | None = None
    comparison_final: Comparison | None = None
    base: dict[str, dict[str, Any]] = field(default_factory=dict)
    unexplained: dict[str, Any] | None = None
    notes: list[str] = field(default_factory=list)
    interrupted: bool = False
    stages: list[DiagnosisStage] = field(default_factory=list, repr=False)
    runs: list[Run] = field(default_factory=list, repr=False)
    #: the files written from it (`plot`: the Rerun recording, the HTML report)
    files: list[Path] = field(default_factory=list)
    #: declared values the calibrated base ends at a bound of (`base_at_bounds`)
    base_at_bounds: list[dict[str, Any]] = field(default_factory=list)
    #: the figures' title (`vtable compare` draws its one model as a diagnosis)
    title: str = "vtable diagnosis"
    #: what the data allow the final model (`limits.limits`: the black box, the bound)
    limits: Limits | None = None
    #: one sentence and the findings a lab engineer reads (`findings`)
    headline: str = ""
    findings: list[dict[str, Any]] = field(default_factory=list)
    #: the specimen's states (`states.state_rows`: state -> its runs and fitted specimen;
    #: empty: one), declared by the runs or (not `states_declared`) one per run
    states: dict[str, dict[str, Any]] = field(default_factory=dict)
    states_declared: bool = False
    #: the force channels' other reading where the runs do not declare it, tried once
    #: (`reading.force_reading`); None: not tried
    force_reading: dict[str, Any] | None = None
    #: a comparison's one model drawn as a diagnosis (`ModelComparison.as_diagnosis`): the
    #: report names "the model", not start and final
    compared: bool = False

    @property
    def final_effects(self) -> list[str]:
        return list(self.final.effects)

    @property
    def reading_kept(self) -> bool:
        """Whether the force channels' other reading was kept (`force_reading`)."""
        fr = self.force_reading
        return fr is not None and fr["found"] != fr["assumed"]

    def steps(self) -> list[Round | dict[str, Any]]:
        """The rounds, and the force reading kept after the round it followed."""
        out: list[Round | dict[str, Any]] = list(self.rounds)
        if self.reading_kept:
            out.insert(self.force_reading["after_round"], self.force_reading)
        return out

    def history(self) -> list[tuple[str, float]]:
        if self.start_error is None:
            return []
        h = [("start", self.start_error)]
        for s in self.steps():
            if isinstance(s, dict):  # the force reading kept
                h.append((READING_STEP.format(s["found"]), s["error_after"]))
            elif s.added:
                h.append((s.added + "".join(f" - {e}" for e in s.removed), s.error))
        return h

    @property
    def localisation(self) -> str:
        """Where the starting model fails, in words and numbers (`prose.localisation_text`)."""
        return localisation_text(self.comparison_start) if self.comparison_start else ""

    def to_json(self) -> dict[str, Any]:
        """The diagnosis JSON (docs/diagnosis-json.md's keys, and more), plain JSON values
        (a non-finite number is null)."""
        return jsonable(self._raw())

    def _raw(self) -> dict[str, Any]:
        """`to_json`'s dictionary with the values as computed (numpy, inf)."""
        return {
            "format": "vtable-diagnosis/1",
            "start_effects": self.start_effects,
            "start_error": self.start_error,
            "noise_floor": self.noise_floor,
            "base": self.base,
            "rounds": [{"ranking": [{"effect": c.effect, "error_after": c.error_after,
                                     "train_error": c.train_error, "params": c.params,
                                     "n_params": c.n_params, "evidence": c.evidence,
                                     "flags": c.flags, "screened": c.screened,
                                     "refined": not (c.screened or c.unrefined),
                                     "gain": _gain_json(c)}
                                    for c in r.ranking],
                        "added": r.added, "removed": r.removed, "error": r.error,
                        "error_before": r.before, "skipped": r.skipped}
                       for r in self.rounds],
            "final_effects": self.final_effects,
            "final_params": {k: v for k, v in self.final.effects.items()},
            "final_base": {"f_o_hz": self.final.open_loop.f_o, "xi_o": self.final.open_loop.xi_o,
                           "k_o_per_s": self.final.open_loop.k_o},
            "final_error": self.final_error,
            "unexplained": self.unexplained,
            "base_at_bounds": self.base_at_bounds,
            "bound": None if self.limits is None else self.limits.bound,
            "reference": None if self.limits is None else self.limits.reference,
            "limits": None if self.limits is None else self.limits.to_json(),
            "headline": self.headline,
            "findings": self.findings,
            "states": self.states,
            "states_declared": self.states_declared,
            "force_reading": self.force_reading,
            "verdict": self.verdict,
            "interrupted": self.interrupted,
            "notes": self.notes,
            "error_definition": ERROR_DEFINITION,
            "unexplained_rule": UNEXPLAINED_RULE,
            "selection_rule": SELECTION,
            "localisation": self.localisation,
        }

    def report(self, verbose: bool = False) -> str:
        """The text `vtable diagnose` prints: the notes, the starting model, each round's
        ranking with its evidence and flags, the error history, the calibrated base, what
        is left unexplained, what the data allow per run and group, the headline and the
        findings, and the files written; `verbose`, the verdict with its statistics."""
        d = self._raw()
        out = []
        for i, n in enumerate(d["notes"]):
            out.append(("notes:\n" if i == 0 else "") + f"  {n}")
        out.append(f"starting model: {linear_model(self.runs)}"
                   + (f" + {', '.join(d['start_effects'])}" if d["start_effects"] else ""))
        out.append(f"  held-out error {d['start_error']:.2%} (noise floor "
                   f"{d['noise_floor']:.2%})")
        out.append(f"  where: {d['localisation']}")
        for i, r in enumerate(d["rounds"], 1):
            out.append(f"\nround {i}: " + (f"added {r['added']}" if r["added"]
                                            else "nothing added"))
            out.append(f"  {'rank':>4}  {'effect':<28} {'held-out':>9}  evidence")
            for k, c in enumerate(r["ranking"], 1):
                out.append(f"  {k:>4}  {c['effect']:<28} {c['error_after']:9.2%}  "
                           + (c["evidence"] if k <= 3 else ""))
                if c.get("flags"):
                    out.append(f"  {'':>4}  {'':<28} {'':>9}  flags: " + "; ".join(c["flags"]))
        out.append("\nerror history: " + " -> ".join(
            f"{e:.2%}" + ("" if step == "start" else f" (+{step})")
            for step, e in self.history()))
        out += base_lines(d["base"])
        for b in d["base_at_bounds"]:
            where = ("beyond its bound (the final model refitted with it widened)"
                     if b["model"] == "widened" else f"at its bound ({b['model']} model)")
            out.append(f"{where}: {b['parameter']} (declared {b['declared']:.4g}, "
                       f"fitted {b['fitted']:.4g}, {b['side']} bound {b['bound']:.4g}); "
                       + (f"--calibrate {b['calibrate']} lets it move" if b["calibrate"]
                          else "its bound is at its widest"))
        u = d["unexplained"]
        out.append("unexplained: " + ("none (the final error is consistent with the noise "
                                      "floor)" if u is None else
                                      f"{u['ratio_to_floor']:.1f} x the noise floor, "
                                      f"{u['where']}"))
        if self.limits is not None and self.limits.groups:
            out.append("what the data allow (held-out, per run and channel group):")
            out.append(self.limits.text())
        if verbose:
            out.append(f"verdict: {d['verdict']}")
        out += finding_lines(self.headline, self.findings)
        out += [f"wrote {f}" for f in self.files]
        return "\n".join(out)

    def plot(self, report: str | Path | None = None, rerun: str | Path | None = None
             ) -> list[Path]:
        """Write the diagnosis's figures from the stages it kept (nothing is simulated
        again): `rerun`, a Rerun recording (.rrd: measured, model and residual of every
        channel group for every stage, the error history); `report`, an HTML report
        (verdict, rankings, the error waterfall, transfer-function overlays). Returns the
        files written (also added to `files`).

        The figures come from `vtable.viz` (matplotlib, rerun), imported here: the
        diagnosis itself needs neither.
        """
        # on use, for the workers' start: vtable.diagnose imports this module, so every
        # spawned candidate worker would load matplotlib and rerun (+0.5 s CPU each)
        wrote = []
        if rerun:
            from vtable.viz.diagnosis_rerun import log_diagnosis

            wrote.append(Path(log_diagnosis(self, rerun)))
        if report:
            from vtable.viz.diagnosis_report import write_report

            wrote.append(Path(write_report(self, report)))
        self.files += wrote
        return wrote



def finding_lines(headline: str, findings: list[dict[str, Any]]) -> list[str]:
    """The headline and the findings as the terminal shows them: what, then what to do."""
    out = [f"headline: {headline}"] if headline else []
    for f in findings:
        out.append(f"  - {f['what']}" + (f" [{', '.join(f['runs'])}]" if f["runs"] else ""))
        out.append(f"    -> {f['action']}")
    return out


class DiagnosisInterrupted(KeyboardInterrupt):
    """Ctrl-C during `Diagnoser.diagnose`: `partial` is the diagnosis of the rounds that
    finished (`interrupted` True)."""

    def __init__(self, partial: Diagnosis) -> None:
        super().__init__(partial.verdict)
        self.partial = partial


def _gain_json(c: Candidate) -> dict[str, float] | None:
    g = c.gain
    if g is None:
        return None
    return {"mean_sq_error_before": g.e2_current, "mean_sq_error_after": g.e2_candidate,
            "mean_sq_noise": g.f2, "gain": g.gain, "noise_se": g.se, "z": g.z,
            "share_of_systematic": g.share, "passes": not c.failing()}


def evidence(c: Candidate, err: float, floor: float, cmp: Comparison) -> str:
    if not np.isfinite(c.error_after):
        return "; ".join(c.flags)
    if c.not_fitted:
        return f"screened out, not fitted: {c.not_fitted}"
    if c.unrefined:
        return (f"passed the screen (held-out error {err:.2%} -> {c.error_after:.2%} where it "
                f"stopped), {c.unrefined}")
    if c.screened:
        return (f"screened out: its first least-squares steps from the best start on its "
                f"grid lowered the training cost by less than {SCREEN:.0%} (held-out error "
                f"{err:.2%} -> {c.error_after:.2%}, not refined further)")
    worst = cmp.worst_groups(2)
    where = ", ".join(g for g, _ in worst)
    band = cmp.worst_band(worst[0][0]) if worst else None
    g = c.gain
    removed = f"{max(g.share, 0.0):.0%}" if g is not None and np.isfinite(g.share) else "all"
    z = f", {g.z_text}" if g is not None else ""
    params = params_text(c.effect, c.params, cmp.display, ".3g")
    return (f"residual concentrated in {where}" + (f" at {band[0]}" if band else "")
            + f"; adding {c.effect} removes {removed} of its systematic part (held-out error "
              f"{err:.2%} -> {c.error_after:.2%}{z}); fitted {params}")



def localise(d: Diagnosis) -> str:
    """`Diagnosis.localisation`."""
    return d.localisation


@dataclass
class ModelComparison:
    """How a model with given effects fits a campaign (`vtable compare`): fitted on the
    training segments with the base calibrated, scored on the held-out ones.

    `effects` and `params` (each effect's fitted parameters, its units), `base` (the
    servo loop's f_o in Hz, ξ_o, k_o in 1/s), `base_fit` (the calibrated base, declared ->
    fitted within bounds), `flags` (fitted parameters at a bound or not identifiable),
    `error` and `noise_floor` (the campaign's held-out NRMS error and the sensor noise's),
    `per_run` (run -> channel group -> NRMS), `bands` (group -> band -> error),
    `localisation` (where it fails, in words), `unexplained` (None when the error is
    consistent with the noise, else the ratio and where: `UNEXPLAINED_RULE`), `notes`.
    """

    effects: list[str]
    params: dict[str, dict[str, float]]
    base: dict[str, float]
    error: float
    noise_floor: float
    per_run: dict[str, dict[str, float]]
    localisation: str
    unexplained: dict[str, Any] | None
    notes: list[str] = field(default_factory=list)
    base_fit: dict[str, dict[str, Any]] = field(default_factory=dict)
    flags: list[str] = field(default_factory=list)
    bands: dict[str, dict[str, float]] = field(default_factory=dict)
    files: list[Path] = field(default_factory=list)
    display: str = "imperial"  # the runs' unit family (`vtable.display`), for the text
    #: the fitted model, its predictions and comparison, for `plot` (not in the JSON)
    model: TableModel | None = field(default=None, repr=False, compare=False)
    predictions: dict | None = field(default=None, repr=False, compare=False)
    comparison: Comparison | None = field(default=None, repr=False, compare=False)
    #: what the data allow the model (`limits.limits`: the black box, the bound)
    limits: Limits | None = None
    #: what the linear model holds (`linear_model`: the specimen, or the bare platen)
    holds: str = "servo loop + specimen"

    @classmethod
    def of(cls, m: TableModel) -> ModelComparison:
        """The comparison of a fitted `TableModel` (scored on the held-out segments)."""
        pred = m.predictions()
        c = m.comparison(predictions=pred)
        ol = m.physics_.open_loop
        return cls(list(m.effects), m.physics_.effects,
                   {"f_o_hz": ol.f_o, "xi_o": ol.xi_o, "k_o_per_s": ol.k_o}, c.error,
                   c.noise_floor, c.per_run, localisation_text(c), unexplained(c),
                   m.notes_, m.base_, m.flags_, c.bands, display=c.display, model=m,
                   predictions=pred, comparison=c, limits=limits(m.campaign_.runs, pred),
                   holds=linear_model(m.campaign_.runs))

    def as_diagnosis(self) -> Diagnosis:
        """The comparison as a diagnosis of no rounds whose one stage is the fitted model,
        for the figures a diagnosis draws (`plot`)."""
        m = self.model
        if m is None:
            raise ValueError("a comparison read back from JSON has no model to plot")
        d = Diagnosis(list(self.effects), self.error, self.noise_floor, [], m.physics_,
                      self.error, f"compare: {self.localisation}", self.comparison,
                      self.comparison, self.base_fit, self.unexplained, list(self.notes),
                      stages=[DiagnosisStage("model", m.physics_, self.predictions)],
                      runs=list(m.campaign_.runs), title="vtable compare", compared=True)
        return d

    def plot(self, report: str | Path | None = None, rerun: str | Path | None = None
             ) -> list[Path]:
        """Write the figures a diagnosis draws (`Diagnosis.plot`) for this one model:
        `rerun` (.rrd: measured, model and residual of every channel group of every run)
        and `report` (HTML: Bode plots with coherence, held-out time histories with fit %,
        the error per channel group). Returns the files written (also added to `files`)."""
        wrote = self.as_diagnosis().plot(report=report, rerun=rerun)
        self.files += wrote
        return wrote

    def to_json(self) -> dict[str, Any]:
        """The JSON `vtable compare --json` writes."""
        return jsonable({"effects": self.effects, "params": self.params, "base": self.base,
                         "base_fit": self.base_fit, "flags": self.flags, "error": self.error,
                         "noise_floor": self.noise_floor, "per_run": self.per_run,
                         "bands": self.bands, "localisation": self.localisation,
                         "unexplained": self.unexplained, "unexplained_rule": UNEXPLAINED_RULE,
                         "bound": None if self.limits is None else self.limits.bound,
                         "reference": None if self.limits is None else self.limits.reference,
                         "limits": None if self.limits is None else self.limits.to_json(),
                         "notes": self.notes})

    def report(self) -> str:
        """The text `vtable compare` prints."""
        out = []
        for i, n in enumerate(self.notes):
            out.append(("notes:\n" if i == 0 else "") + f"  {n}")
        out.append(f"model: {self.holds}"
                   + (f" + {', '.join(self.effects)}" if self.effects else ""))
        b = self.base
        out.append(f"  base loop: f_o {b['f_o_hz']:.2f} Hz, ξ_o {b['xi_o']:.3f}, "
                   f"k_o {b['k_o_per_s']:.2f}")
        for e, p in self.params.items():
            out.append(f"  {e}: " + params_text(e, p, self.display))
        out += [f"  flag: {f}" for f in self.flags]
        out += base_lines(self.base_fit, indent="  ")
        out.append(f"  held-out error {self.error:.2%}, noise floor {self.noise_floor:.2%}")
        for run, errs in self.per_run.items():
            out.append(f"  {run}: " + ", ".join(f"{g} {e:.1%}" for g, e in errs.items()))
        out.append(f"  where: {self.localisation}")
        u = self.unexplained
        out.append("  unexplained: " + ("none (the error is consistent with the noise floor)"
                                        if u is None else
                                        f"{u['ratio_to_floor']:.1f} x the noise floor, "
                                        f"{u['where']}"))
        if self.limits is not None and self.limits.groups:
            lim = self.limits
            out.append(f"  what the data allow: black box {_pct(lim.reference)}, bound "
                       f"{_pct(lim.bound)}; the error is noise {_pct(lim.noise)}, within "
                       f"reach {_pct(lim.within_reach)}, beyond {_pct(lim.beyond)}")
            out.append(lim.text())
        out += [f"wrote {f}" for f in self.files]
        return "\n".join(out)


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{v:.2%}"
