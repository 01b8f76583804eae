"""Whether a run's command column is the command its table followed, in time and in scale:
what a diagnosis says when its final model loses to the black box on a run (`findings`'
`command_offset` and `command_scale`).

A lab's drive may be logged on another clock than its sensors (LNEC's run file says its
drive and acquisition were not aligned by the lab). Every response then carries a pure
delay e^{-jωτ} that no physics of the table holds: the servo loop is fitted to stand in
for it, nothing is added, and the model ends far above the black box (LNEC's run with its
command column shifted by 50 ms: 84.9 % against 22.7 %, f_o at its bound; aligned, 18 %).

For each run whose final model's held-out error (the mean over its groups) is above the
black box's, the lag of the command column behind the acquisition beyond what the servo
loop explains is estimated as a drive file's "auto" offset is
(`vtable.ident.drive.estimate_offset`: the loop structures with a pure delay fitted to the
H1 of x_t over the command). A lag of at least `MIN_SAMPLES` samples and `MIN_Z` standard
errors is then tried: the starting model is refitted on the campaign with those runs'
commands shifted by it (whole samples), and it is said only when the run's held-out error
falls by at least `MIN_GAIN` of the starting model's (a lag that buys nothing, a loop
structure's delay standing in for an undeclared specimen, is not said). The starting
model, not the final one: the effects a diagnosis added on the misaligned runs stood in
for the lag (the same run with its command 50 ms early instead: two sensor filters and an
offset added), and a refit from there keeps them. The check costs a diagnosis nothing
unless a run loses to the black box; then an estimate (under a second to a few on a
real-size run) and, for a lag or a scale worth trying, one to three refits of the
starting model.

The shift is said in the run file's own samples (its rate, not the analysis rate) and in
seconds; for a command made from a drive file as the drive_offset_s that undoes it. A run
that loses but cannot be tested (no table displacement, too short) is said so in the
notes.

The same estimate measures x_t/x_c's DC gain (`vtable.ident.loop.dc_gain`, from the
lowest resolved lines, no model of the loop). A valve-integrator loop follows a static
command exactly (type 1: gain 1, a specimen on the table or not); a gain off 1 by more than
`vtable.ident.loop.DC_TOL` and `MIN_Z` standard errors (every table vtable models is a
valve-integrator's, its declared controller's loop included) says the column does not
read the command the table was given (its unit, a span's calibration: a column in inches
read as mm is off 25.4 times). It is tried and said as the lag is: the starting model
refitted with the command scaled by the gain; on a run with both, each is also tried
after the other (`_taken`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from vtable.errors import VtableError
from vtable.ident.drive import estimate_offset
from vtable.ident.loop import DC_TOL
from vtable.runs.drive import FROM_DRIVE, DriveFile, with_command
from vtable.runs.model import Run

#: a lag of fewer samples is within what the estimate and the sampling can say ...
MIN_SAMPLES = 2.0
#: ... and of fewer standard errors is not told from none
MIN_Z = 5.0
#: the run's held-out error must fall by this share of itself with its command shifted
MIN_GAIN = 0.2


@dataclass(frozen=True)
class CommandOffset:
    """A run whose command column lags (`offset` > 0) or leads the acquisition by
    `offset` s (± `stderr`) beyond the servo loop's own delay, and the run's held-out
    error of the starting model before and after its refit with the command shifted by
    `samples` whole samples; `reference` is the black box's."""

    run: str
    offset: float
    stderr: float
    fs: float  # the run file's rate
    samples: int  # the run file's samples it was moved by
    before: float
    after: float
    reference: float
    #: the drive_offset_s the run's drive file was played at (s, or "auto"), None for an
    #: h_span column
    drive_offset: float | str | None = None
    kind = "command_offset"

    def numbers(self) -> dict[str, float]:
        return {"offset_s": self.offset, "stderr_s": self.stderr, "samples": self.samples,
                "error_before": self.before, "error_after": self.after,
                "reference": self.reference}

    def text(self) -> str:
        side = "lags" if self.offset > 0 else "leads"
        what = "command" if self.drive_offset is not None else "command column"
        return (f"the {what} {side} the acquisition by {abs(self.offset) * 1e3:.3g} "
                f"± {self.stderr * 1e3:.2g} ms ({abs(self.offset) * self.fs:.1f} samples at "
                f"{self.fs:g} Hz) beyond the servo loop's own delay (x_t's H1 over the "
                f"command fitted by the loop with a pure delay); moved back by "
                f"{abs(self.samples)} samples, {_refitted(self)}")

    def action(self) -> str:
        if self.drive_offset == "auto":
            return ("drive_offset_s = \"auto\" left this lag: give drive_offset_s in seconds, "
                    f"the lag the reader's note gives {self.samples / self.fs:+.4g} s, and "
                    "diagnose again")
        if self.drive_offset is not None:
            return ("if the drive file's offset is off, set drive_offset_s = "
                    f"{self.drive_offset + self.samples / self.fs:.6g} (now "
                    f"{self.drive_offset:g}) and diagnose again")
        return ("if the drive and the acquisition were not time-aligned, align them and "
                "diagnose again: give the command as a drive file with drive_offset_s = "
                f'"auto" (docs/run-format.md), or shift the h_span column by {self.samples:+d} '
                f"samples ({self.samples / self.fs:+.4g} s; later values earlier)")


@dataclass(frozen=True)
class CommandScale:
    """A run whose table follows `gain` (± `stderr`) times its command column at DC where
    its type-1 loop follows 1 x, and the run's held-out error of the starting model before
    and after its refit with the command scaled by `gain`; `reference` is the black
    box's."""

    run: str
    gain: float
    stderr: float
    before: float
    after: float
    reference: float
    #: the drive_scale the run's drive file was played at, None for an h_span column
    drive_scale: float | None = None
    kind = "command_scale"

    def text(self) -> str:
        return (f"the table's displacement follows the command with a DC gain of "
                f"{self.gain:.4g} ± {self.stderr:.2g}, where its servo loop's is 1 (a "
                "valve-integrator loop follows a static command exactly): the command reads "
                f"{1 / self.gain:.4g} x what the table was given; scaled by {self.gain:.4g}, "
                f"{_refitted(self)}")

    def action(self) -> str:
        if self.drive_scale is not None:
            return ("check the drive file's unit and scale: if they are off, set drive_scale "
                    f"= {self.drive_scale * self.gain:.4g} (now {self.drive_scale:g}) and "
                    "diagnose again")
        return ("check the command column's unit ([units] h_span) and the span's "
                f"calibration: if it is off, correct it (x {self.gain:.4g}) and diagnose "
                "again")

    def numbers(self) -> dict[str, float]:
        return {"gain": self.gain, "stderr": self.stderr, "error_before": self.before,
                "error_after": self.after, "reference": self.reference}


def _refitted(c: CommandOffset | CommandScale) -> str:
    """What the starting model's refit with the command so changed gives on the run."""
    return (f"the starting model refitted reaches {c.after:.1%} on the run, from "
            f"{c.before:.1%} (the black box {c.reference:.1%})")


def command_checks(d, diag, said: Callable[[str], None] = lambda s: None
                   ) -> list[CommandOffset | CommandScale]:
    """The runs of diagnoser `d` whose command column is found out of time or out of scale
    with what their table followed (module docstring), from its `Diagnosis` `diag`
    (limits per group, the starting model's comparison); a losing run that cannot be
    tested is said in its notes. `said` hears what is being tested, when anything is."""
    lim, start = diag.limits, diag.comparison_start
    if lim is None or start is None or diag.interrupted:
        return []
    losing = {run: ref for run, (err, ref) in lim.by_run().items()
              if err > ref and start.per_run.get(run)}  # run -> the black box's error
    if not losing:
        return []
    said("testing whether the command column is the command the table followed")
    lags, gains = {}, {}
    for r in d.runs:
        if r.name not in losing:
            continue
        try:
            est = estimate_offset(r, _column(r), None, r.name)
        except (VtableError, ValueError, ArithmeticError, np.linalg.LinAlgError) as e:
            diag.notes.append(f"{r.name}: the model loses to the black box, and whether its "
                              f"command column is the command the table followed could not "
                              f"be tested: {e}")
            continue
        if abs(est.samples) >= MIN_SAMPLES and abs(est.offset) >= MIN_Z * est.stderr:
            lags[r.name] = est
        g, sg = est.structure.dc
        if math.isfinite(g) and g > 0 and abs(g - 1) > max(MIN_Z * sg, DC_TOL):
            gains[r.name] = (g, sg)
    taken = _taken(d, diag, start, lags, gains)
    source = {r.name: r for r in d.source_runs}
    out: list[CommandOffset | CommandScale] = []
    for (kind, name), (before, now) in taken.items():
        src = source.get(name)
        cmd = None if src is None or not any(FROM_DRIVE in x for x in src.reports) \
            else src.drive()  # a command the reader made from a drive file
        if kind == "lag":
            est = lags[name]
            fs = src.fs if src is not None else est.fs
            given = cmd.drive_offset if cmd is not None else None
            out.append(CommandOffset(name, est.offset, est.stderr, fs, round(est.offset * fs),
                                     before, now, losing[name], given))
        else:
            given = (cmd.drive_scale or 1.0) if cmd is not None else None
            out.append(CommandScale(name, *gains[name], before, now, losing[name], given))
    return out


def _taken(d, diag, start, lags: dict, gains: dict) -> dict[tuple[str, str], tuple]:
    """The lags and scales found that the starting model's refit confirms: ("lag" or
    "scale", run) -> (the run's held-out error without it, with it). Each is applied
    alone (its run's error must fall by `MIN_GAIN` of the starting model's) and, on a run
    with both, also after the other (its error must fall by `MIN_GAIN` of the other's
    alone): a lag and a scale error together may each gain little alone. At most three
    refits (lags, scales, both)."""
    def err(after: dict, name: str) -> float:
        v = list(after.get(name, {}).values())
        return float(np.mean(v)) if v else math.inf

    def refit(shift: bool, scale: bool) -> dict:
        runs = []
        for r in d.runs:
            if scale and r.name in gains:
                r = _scaled(r, gains[r.name][0])
            if shift and r.name in lags:
                r = _shifted(r, round(lags[r.name].samples))
            runs.append(r)
        try:  # the starting model (what later effects stood in for is not theirs to undo)
            return d.model(d.start).fit(runs).comparison(detail=False).per_run
        except (VtableError, ValueError, ArithmeticError, np.linalg.LinAlgError) as e:
            diag.notes.append(f"the starting model could not be refitted with the runs' "
                              f"commands as the checks of their columns found them: {e}")
            return {}

    before = {name: float(np.mean(list(start.per_run[name].values())))
              for name in {*lags, *gains}}
    alone = {"lag": refit(True, False) if lags else {},
             "scale": refit(False, True) if gains else {}}
    both = refit(True, True) if set(lags) & set(gains) else {}
    out = {}
    for kind, found, other in (("lag", lags, "scale"), ("scale", gains, "lag")):
        for name in found:
            if err(alone[kind], name) <= (1 - MIN_GAIN) * before[name]:
                out[(kind, name)] = (before[name], err(alone[kind], name))
            elif name in lags and name in gains and \
                    err(both, name) <= (1 - MIN_GAIN) * err(alone[other], name):
                out[(kind, name)] = (err(alone[other], name), err(both, name))
    return out


def _scaled(run: Run, g: float) -> Run:
    """`run` with its command h_span times `g`."""
    return dataclasses.replace(run, channels={**run.channels, "h_span": g * run.channel("h_span")})


def _column(run: Run) -> DriveFile:
    """The run's command h_span as a drive file (what `estimate_offset` and
    `with_command` take)."""
    return DriveFile(Path(f"{run.name} h_span"), run.time, run.channel("h_span"), "m", 1.0)


def _shifted(run: Run, k: int) -> Run:
    """`run` with its command h_span moved by `k` whole samples (`with_command`: its
    column as a drive file at that offset)."""
    bare = dataclasses.replace(run, channels={c: v for c, v in run.channels.items()
                                              if c != "h_span"})
    return with_command(bare, _column(run), k * run.dt, f"shifted by {k:+d} samples", run.name)
