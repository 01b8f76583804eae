"""What identification finds that a run does not declare: a resonance on the platen
(`vtable.ident.resonator`), read from x_t/x_c by identify's structure check
(`loop.compare_structures`, eq 7.9 with the valve lag against the loop alone). The
diagnosis takes it as evidence for `platen_resonator` (issue 32: a heavy undocumented
specimen is not charged as implausible when the run's own x_t/x_c shows it)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vtable.errors import VtableError
from vtable.ident import channels
from vtable.ident.frames import MIN_AVERAGES, frame_for_averages
from vtable.ident.loop import AIC_MARGIN, LoopData, aic, compare_structures, prior_of
from vtable.ident.report import servo_band
from vtable.ident.resonator import RESONANCE_MAX_DAMPING
from vtable.ident.tf import transfer_function
from vtable.params.specimen import NoSpecimen, RigidBlock
from vtable.runs.lab import run_table
from vtable.runs.model import Run


@dataclass(frozen=True)
class Resonance:
    """A resonance on the platen a run does not declare: its frequency (Hz), damping ratio
    and mass over the platen's (u = m_s/m_t, eq 7.9); the damping or the mass None where
    the record does not resolve it (a short record: an earthquake's few averages)."""

    run: str
    f_s: float
    xi_s: float | None
    u: float | None


#: the bands (Hz) in which the table acceleration is compared with s² times the table
#: displacement, from the bottom, and how far their ratio may stray from 1 there
BANDS = ((0.0, 2.0), (2.0, 5.0), (5.0, 10.0), (10.0, 20.0), (20.0, 30.0), (30.0, 50.0))
AGREE = 1.25


def _agreeing(run: Run, tf, n: int) -> float:
    """The top (Hz) of the bands, from the bottom, where the run's table acceleration is s²
    times its table displacement within a factor `AGREE` (median |ẍ/s²x| per band): there
    the displacement reads the platen that a resonator on it moves. Above, the two sensors
    part (a displacement-only notch, an accelerometer's mount) and a resonance fitted to
    x_t/x_c could be the sensor's rather than the platen's. Infinite without the channel."""
    if not run.has("avg_hacc") or run.missing.get("avg_hacc"):
        return np.inf
    acc = transfer_function(run.channel("h_span"), run.channel("avg_hacc"), run.fs, n)
    w2 = (2 * np.pi * tf.f) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.abs(acc.H / (-w2 * tf.H))
    top = 0.0
    for a, b in BANDS:
        sel = (tf.f > max(a, 0.2)) & (tf.f <= b) & np.isfinite(ratio)
        if not sel.any():
            break
        r = float(np.median(ratio[sel]))
        if not 1 / AGREE <= r <= AGREE:
            break
        top = b
    return top if top > 0 else np.inf


def undeclared_resonance(run: Run) -> Resonance | None:
    """The resonance identify's structure check finds on `run`'s x_t/x_c, where the run
    declares no specimen with a mode (none, or a rigid block) and the resonator structure
    wins (`loop.compare_structures`), or its frequency alone where the record resolves
    only that (`_frequency_only`); None otherwise, or when the run cannot be fitted."""
    spec = run.specimen()
    if not isinstance(spec, NoSpecimen | RigidBlock):
        return None
    try:
        table = run_table(run)
        x_c, x_t = channels.require(run, "h_span", "avg_hdisp", purpose="x_t/x_c")
        n = frame_for_averages(len(run.time), MIN_AVERAGES, longest=2048)
        if n is None:
            return None
        tf = transfer_function(x_c, x_t, run.fs, n)
        lo, hi = servo_band(run, table)
        ls = compare_structures(LoopData.from_tf(tf, (lo, min(hi, _agreeing(run, tf, n)))),
                                prior_of(table))
    except VtableError:
        return None
    if not ls.fits_eq_6_15:
        return None
    if ls.best == "resonator":
        fit = ls.fits["resonator"]
        return Resonance(run.name, float(fit["f_s"]), float(fit["xi_s"]), float(fit["u"]))
    return _frequency_only(run, ls)


def _frequency_only(run: Run, ls) -> Resonance | None:
    """A resonance the record resolves only in part: the resonator's fit that the
    comparison left out (`LoopStructure.rejected`: its damping or mass flagged) wins by
    `AIC_MARGIN` over every other structure, its frequency resolved, its mass not at a
    bound (a PI controller's low-frequency peak once asked for a resonator at the table's
    payload); what it does not resolve is None. None otherwise."""
    fit = ls.rejected
    if fit is None or not ls.aic:
        return None
    flags = {(f.param, f.code) for f in fit.flags if f.code != "correlated"}
    flagged = {p for p, _ in flags}
    if not aic(fit) + AIC_MARGIN < min(ls.aic.values()) or "f_s" in flagged \
            or ("u", "at_bound") in flags \
            or ("xi_s" not in flagged and fit["xi_s"] > RESONANCE_MAX_DAMPING):
        return None
    return Resonance(run.name, float(fit["f_s"]),
                     None if "xi_s" in flagged else float(fit["xi_s"]),
                     None if "u" in flagged else float(fit["u"]))
