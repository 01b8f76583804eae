"""Drive alignment: drive_offset_s = "auto", the lag of a drive file behind the
acquisition identified from the table's response (docs/run-format.md).

The reader leaves such a run without its command (`vtable.runs.drive.AUTO_PENDING`);
`align` estimates the offset and makes the command h_span from the drive file.

The table itself delays its response (a valve-integrator loop has a DC group delay of
about 1/k_o plus the valve lag), so the lag of x_t behind the drive is not the offset.
The offset is estimated in two steps: a coarse alignment o₀ at the peak of the
cross-correlation of drive and x_t (avg_hdisp), then the complex H1 of x_t over the drive
aligned at o₀ is fitted by the candidate loop structures each with a pure delay e^{jωΔ}
(`vtable.ident.loop.compare_structures`: eq 6.15, eq 6.15 x a first-order valve lag, a
type-0 loop; started from the run's table, eq 6.16 and its valve time constant); the best
structure's Δ gives o = o₀ + Δ, its standard error the uncertainty. When the record does
not tell the structures apart, Δ is fitted alone with the table's described loop held.
The offset used is o rounded to whole samples of the run (lost samples are whole
samples); the report line gives both.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from vtable.errors import VtableError
from vtable.ident import channels
from vtable.ident.frames import MIN_AVERAGES, frame_for_averages
from vtable.ident.loop import (
    LoopData,
    LoopStructure,
    compare_structures,
    fit_delay_held,
    prior_of,
    resolved,
)
from vtable.ident.tf import transfer_function
from vtable.runs.drive import (
    AUTO_PENDING,
    DriveFile,
    coarse_offset,
    on_grid,
    read_drive,
    with_command,
)
from vtable.runs.lab import run_table
from vtable.runs.model import Run


@dataclass(frozen=True)
class OffsetEstimate:
    """drive_offset_s = "auto": the offset (s), its standard error, the coarse alignment
    and the loop structures it was fitted with."""

    offset: float
    stderr: float
    coarse: float
    structure: LoopStructure
    fs: float
    how: str = ""

    @property
    def samples(self) -> float:
        return self.offset * self.fs

    def to_json(self) -> dict[str, Any]:
        return {"offset_s": self.offset, "offset_samples": self.samples,
                "stderr_s": self.stderr, "stderr_samples": self.stderr * self.fs,
                "coarse_offset_s": self.coarse, "how": self.how,
                "loop": self.structure.to_json()}


def estimate_offset(run: Run, drive: DriveFile, band: tuple[float, float] | None,
                    where: str) -> OffsetEstimate:
    """drive_offset_s = "auto" (module docstring): the coarse alignment, then the delay
    fitted jointly with the loop structures on the complex H1 of avg_hdisp over the
    drive. `where` names the [command] table in messages."""
    why = channels.channel_problem(run, "avg_hdisp")
    if why:
        raise VtableError(f"{where}.drive_offset_s: \"auto\" estimates the lag from the "
                          f"table's response, but {why}; give the offset in seconds")
    y = run.channels["avg_hdisp"]
    coarse = coarse_offset(drive, run.time, y)
    x0, _ = on_grid(drive, run.time, coarse)
    n = frame_for_averages(len(y), MIN_AVERAGES, longest=2048) or \
        frame_for_averages(len(y), 2)
    if n is None:
        raise VtableError(f"{where}.drive_offset_s: \"auto\": the run ({len(y)} samples) is "
                          "too short to estimate the lag; give the offset in seconds")
    tf = transfer_function(x0, y, run.fs, n)
    hi = 0.45 * run.fs if band is None else min(band[1], 0.45 * run.fs)
    lo = max(0.2, 3 * run.fs / n)
    table = run_table(run)
    prior = prior_of(table)
    try:
        data = LoopData.from_tf(tf, (lo, hi), min_coherence=0.8)
        st = compare_structures(data, prior, delay_dt=run.dt)
    except VtableError as e:
        raise VtableError(f"{where}.drive_offset_s: \"auto\": cannot fit the lag ({e}); give "
                          "the offset in seconds") from None
    fit = st.fits[st.best]
    how = f"{st.candidates[st.best].name} x e^(-jωδ), fitted jointly"
    if not resolved(st):
        fit = fit_delay_held(data, prior, run.dt)
        how = (f"the loop of the table's description ({table.name}: eq 6.16, valve lag "
               f"{prior.tau:g} s) x e^(-jωδ), δ alone: the record does not tell the loop "
               f"structures apart ({len(data.f)} lines)")
    delay, sd = fit.params["delay"], fit.stderr["delay"]
    return OffsetEstimate(coarse + delay, sd, coarse, st, run.fs, how)


def align(run: Run) -> Run:
    """The run with its command h_span made from its drive file at the estimated offset
    when its [command] says drive_offset_s = "auto" and it has no h_span column; any
    other run unchanged.

    Parameters
    ----------
    run
        A run as read (`vtable.runs.read_run`).

    Returns
    -------
    Run
        h_span added; the reader's pending line replaced by one naming the drive file,
        its scale, the lag used (whole samples) and the estimate with its uncertainty.

    Raises
    ------
    VtableError
        One line naming the [command] key when the lag cannot be estimated.
    """
    cmd = run.drive()
    if run.has("h_span") or cmd is None or cmd.drive_file is None or \
            cmd.drive_offset != "auto":
        return run
    where = str(run.source) if run.source is not None else run.name
    key = f"{where} [command]"
    drive = read_drive(cmd.drive_file, cmd.drive_unit, cmd.drive_scale, key)
    est = estimate_offset(run, drive, cmd.band, key)
    offset = round(est.samples) * run.dt
    how = (f"estimated lag {round(est.samples)} samples ({offset:.4g} s): "
           f"{est.samples:.2f} ± {est.stderr * run.fs:.2g} samples, from the "
           f"H1 of avg_hdisp over the drive with {est.how}")
    pending = f"{where}: {AUTO_PENDING}"
    reports = [r for r in run.reports if r != pending]
    out = with_command(dataclasses.replace(run, reports=reports), drive, offset, how, where)
    if pending in run.reports:  # the drive line where the reader's pending line was
        i = run.reports.index(pending)
        out.reports = [*reports[:i], out.reports[-1], *reports[i:]]
    return out
