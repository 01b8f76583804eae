"""The measured runs' verbs: the identification of a campaign, and the transfer function
of a run by H1 with coherence (`tf` takes a run or a model: `is_run` tells which)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from vtable.errors import VtableError
from vtable.ident import channels, transfer_function
from vtable.ident.drive import align
from vtable.ident.frames import (
    FEWEST_AVERAGES,
    MIN_AVERAGES,
    averages,
    frame_for_averages,
    frame_for_mode,
)
from vtable.ident.report import identify_run
from vtable.ident.structure import lowest_declared_mode
from vtable.params.base import read_toml
from vtable.results import CampaignIdentification, FrequencyResponse
from vtable.runs import campaign, read_any
from vtable.verbs.analytic import config_tf


def is_run(path: str) -> bool:
    """Whether `path` names a run (an HDF5 file, or a TOML with a `format` key) rather
    than a model file or a configuration name."""
    p = Path(path)
    if p.suffix in (".h5", ".hdf5"):
        return True
    if p.suffix.lower() == ".csv":  # a run's data: read through its run file
        if p.with_suffix(".toml").is_file():
            return True
        raise VtableError(f"{p}: a run's data (CSV); its run file {p.with_suffix('.toml')}, "
                          "which declares its table, units and specimen, is not beside it")
    if p.suffix != ".toml" or not p.is_file():
        return False
    return "format" in read_toml(p)  # model files have no format key


def tf(config: str, out: str = "x_t", inp: str = "x_c", fmin: float = 0.5, fmax: float = 20.0,
       n: int = 40, log: bool = False, nperseg: int | None = None,
       png: str | None = None) -> FrequencyResponse:
    """A frequency response: of a model (at n frequencies, `config_tf`), or of a run by H1
    with coherence (`run_tf`)."""
    if is_run(config):
        return run_tf(config, out, inp, fmin, fmax, nperseg, png)
    return config_tf(config, out, inp, fmin, fmax, n, log, png)


def run_tf(path: str, out: str = "x_t", inp: str = "x_c", fmin: float = 0.5,
           fmax: float = 20.0, nperseg: int | None = None,
           png: str | None = None) -> FrequencyResponse:
    """H1 with coherence between two channels of a run. The frames (unless `nperseg` says
    otherwise) resolve the declared specimen's lowest fixed-base mode
    (`vtable.ident.frames.frame_for_mode`: the peak and notch the report is about), else
    give >= 8 averages; too few averages are warned."""
    run = align(read_any(path))
    out = "avg_hdisp" if out == "x_t" else out
    inp = "h_span" if inp == "x_c" else inp
    x, y = run.channel(inp), run.channel(out)
    for name, kind in ((inp, "input"), (out, "output")):
        why = channels.channel_problem(run, name)
        if why:
            raise VtableError(f"{run.name}: {why}: no transfer function with it as the {kind}")
    if not (0 <= fmin < fmax):
        raise VtableError(f"need 0 <= --fmin < --fmax, got {fmin:g}, {fmax:g}")
    n_samples, warnings = len(x), []
    n8 = frame_for_averages(n_samples, MIN_AVERAGES)
    if nperseg is not None:
        if not 16 <= nperseg <= n_samples:
            raise VtableError(f"--nperseg must be between 16 and the run's {n_samples} samples, "
                              f"got {nperseg}")
        n, why = nperseg, "given --nperseg"
    elif (choice := _mode_frames(run, n_samples)) is not None:
        n, why = choice
    elif n8 is not None:
        n, why = n8, f"the longest power-of-two frame giving >= {MIN_AVERAGES} averages"
    else:
        n = frame_for_averages(n_samples, FEWEST_AVERAGES)
        if n is None:
            raise VtableError(f"{run.name}: {n_samples} samples are too short for a transfer "
                              f"function of {FEWEST_AVERAGES} averages")
        why = f"the record is too short for {MIN_AVERAGES} averages of 64-point frames"
    nd = averages(n_samples, n)
    better = f"; --nperseg {n8} gives {averages(n_samples, n8)}" if n8 and n8 != n else ""
    if nd <= 1:
        warnings.append(f"1 average ({n} of {n_samples} samples): the coherence is 1 by "
                        f"construction and means nothing; the estimate is not averaged{better}")
    elif nd < MIN_AVERAGES:
        warnings.append(f"{nd} averages (< {MIN_AVERAGES}): large random error, coherence "
                        f"biased towards 1{better}")
    est = transfer_function(x, y, run.fs, n)
    sel = (est.f >= fmin) & (est.f <= fmax)
    r = FrequencyResponse(run.name, out, inp, est.f[sel], est.H[sel],
                          f"{run.name}: {out}/{inp} ({nd} averages)", est.coherence[sel],
                          est.averages, n, run.fs / n, why, nd > 1, warnings, list(run.reports))
    if png:
        r.plot(png)
    return r


def _mode_frames(run, n_samples: int) -> tuple[int, str] | None:
    """The frames that resolve the run's declared specimen's lowest mode and why; None
    when it declares none, or when the record cannot hold a fit of it (the averages' rule
    then, the reason in the notes)."""
    mode = lowest_declared_mode(run)
    if mode is None:
        return None
    f_n, xi_n = mode
    try:
        c = frame_for_mode(n_samples, run.fs, f_n, xi_n, "the declared specimen's mode")
    except VtableError as e:
        run.reports.append(f"{e}: frames chosen for averages instead")
        return None
    return c.nperseg, f"the declared specimen's lowest mode ({f_n:.3g} Hz, ξ {xi_n:.3g}): {c.why}"


def identify(paths: Sequence[str]) -> CampaignIdentification:
    """The report's identification of every run of one configuration."""
    return CampaignIdentification([identify_run(align(r)) for r in campaign(paths)])
