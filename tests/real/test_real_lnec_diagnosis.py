"""Issue 32's acceptance on LNEC's measured run (../shared/data/real): diagnosed alone, as
shipped, with the catalog, the final held-out error is at or below the black-box reference
(the H1 of each table channel over the command on the diagnosis's training window, played
as a centred FIR: recomputed here in a few lines that share no code with vtable), and what
the runs show is in the model with fitted values: the accelerometer's mount and zero, the
undeclared specimen (a resonator near the 3.2 Hz notch) and its softening during the run.

Measured (2026-11-28): 41.0 % -> 31.7 % (+sensor_mount) -> 25.9 % (+platen_resonator, m_r
58 %, f_r 3.19 Hz) -> 22.6 % (+sensor_offset, -0.0079 g) -> 18.0 % (+specimen_degradation,
δ 0.025, n 1.21), reference 23.04 %; 45 s."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
import real_data
import scipy.signal as sg
from conftest import made_once

from vtable.diagnose.engine import Diagnoser
from vtable.diagnose.model import TableModel
from vtable.ident.undeclared import undeclared_resonance
from vtable.runs import read_run

pytestmark = real_data.NEEDED


def _reference(run) -> float:
    """The black box, independently: the mean over the two table channels of the held-out
    NRMS of an H1 -> centred-FIR predictor trained on min(60 %, 30 s), best of three
    frames."""
    x = run.channels["h_span"]
    n, fs = len(x), run.fs
    cut = round(0.6 * n)
    tr, ho = slice(0, min(cut, round(30 * fs) + 1)), slice(cut, n)
    errs = []
    for ch in ("avg_hdisp", "avg_hacc"):
        y, best = run.channels[ch], np.inf
        for nf in (256, 512, 1024):
            _, sxy = sg.csd(x[tr], y[tr], nperseg=nf)
            _, sxx = sg.welch(x[tr], nperseg=nf)
            h = np.roll(np.fft.irfft(sxy / np.where(sxx > 1e-6 * sxx.max(), sxx, np.inf), nf),
                        nf // 2)
            yh = np.convolve(x, h)[nf // 2:nf // 2 + n]
            best = min(best, np.linalg.norm(yh[ho] - y[ho]) / np.linalg.norm(y[ho]))
        errs.append(best)
    return float(np.mean(errs))


@pytest.fixture(scope="module")
def diagnosis(tmp_path_factory):
    def make(folder):
        run = read_run(real_data.copy_run(folder))
        return run, Diagnoser([run]).diagnose()

    return made_once(tmp_path_factory, "lnec_diagnosis", make)


def test_the_catalog_reaches_the_black_box(diagnosis):
    run, d = diagnosis
    ref = _reference(run)
    assert ref == pytest.approx(0.2304, abs=0.002)
    assert d.limits.reference == pytest.approx(ref, rel=1e-3)
    assert d.final_error <= 0.85 * ref, (d.final_error, ref, d.headline)  # 18.0 % vs 23.0
    # each added effect lowered the error, the first from 41 %
    errors = [d.start_error] + [r.error for r in d.rounds if r.added]
    assert errors[0] > 0.38 and all(b < a for a, b in itertools.pairwise(errors))


def test_what_the_run_shows_is_in_the_model_with_fitted_values(diagnosis):
    run, d = diagnosis
    assert set(d.final_effects) == {"sensor_mount", "platen_resonator", "sensor_offset",
                                    "specimen_degradation"}, d.headline
    res = d.final.effects["platen_resonator"]
    assert 3.0 < res["f_r"] < 3.4 and 20.0 < res["m_r"] < 150.0, res  # the 3.2 Hz specimen
    mean_g = np.mean(run.channels["avg_hacc"][: round(0.6 * len(run.time))]) / 9.80665
    assert d.final.effects["sensor_offset"]["offset"] == pytest.approx(mean_g, rel=0.05)
    kinds = {f["kind"] for f in d.findings}
    assert {"effect_added", "softening", "sensor"} <= kinds
    soft = next(f for f in d.findings if f["kind"] == "softening")
    assert soft["numbers"]["last_hz"] < soft["numbers"]["first_hz"] - 0.1
    assert "follows it with specimen_degradation" in soft["action"]
    # the softening is tried last, on the model the time-invariant effects made
    assert d.rounds[-1].added == "specimen_degradation"
    assert 1e-3 < d.final.effects["specimen_degradation"]["delta"] < 0.3
    assert len(d.headline) <= 200 and d.headline.startswith("added ")


def test_the_model_the_findings_name_compares_as_the_diagnosis_ended(diagnosis):
    """The last effect_added finding's flag (`--with` the final effects) refits the same
    model: `compare --with` starts each effect where the runs show it, as the diagnosis does.
    Measured: 18.01 % both (from the effects' defaults the one fit ended at 27.1 %, the
    resonator at its bounds)."""
    run, d = diagnosis
    action = [f["action"] for f in d.findings if f["kind"] == "effect_added"][-1]
    named = action.split("--with ")[1].rstrip(")").split(",")
    assert named == d.final_effects
    m = TableModel(named).fit([run])
    assert m.comparison(detail=False).error == pytest.approx(d.final_error, abs=0.003)
    assert not m.flags_ and any("platen_resonator: the runs show" in n for n in m.notes_)

@pytest.mark.parametrize("part", ["first", "last"])
def test_the_undeclared_specimen_is_found_on_any_100_s_of_the_run(tmp_path, part):
    """The evidence for the undeclared specimen is read where the two table channels agree
    (|ẍ/s²x| within 1.25 of 1: up to 10 Hz here): above, a displacement-only notch at 16 Hz
    once won the one-resonator fit on the run's last 100 s (f_s 16.4 Hz, u 0.97), which then
    kept the 3 Hz specimen out of the model (25.4 % against a 15.8 % black box)."""
    found = undeclared_resonance(_window(tmp_path, part))
    assert found is not None and found.u is not None and found.xi_s is not None, found
    assert 2.9 < found.f_s < 3.2 and 0.3 < found.u < 0.7, found


def _window(tmp_path, part: str):
    """The run's first or last 100 s, as a run of its own."""
    run = read_run(real_data.copy_run(tmp_path))
    k = 100 * round(run.fs)
    keep = slice(0, k) if part == "first" else slice(len(run.time) - k, None)
    return dataclasses.replace(run, time=run.time[keep] - run.time[keep][0],
                               channels={c: v[keep] for c, v in run.channels.items()})


@pytest.mark.parametrize("part", ["first", "last"])
def test_any_100_s_of_the_run_diagnosed_alone_reaches_its_black_box(tmp_path, part):
    """What stands for the lab's other runs (held out): a window of this one, diagnosed
    alone as shipped. Measured: first 100 s 22.0 % against 23.0 % (mount, specimen, zero);
    last 100 s 14.8 % against 15.8 % (the same, and a compliant reaction at 8.6 Hz: the
    displacement transducers read the platen relative to a reaction that moves; 17.2 %
    without it)."""
    window = _window(tmp_path, part)
    d = Diagnoser([window]).diagnose()
    assert d.final_error <= _reference(window), d.headline
    assert {"sensor_mount", "platen_resonator"} <= set(d.final_effects), d.headline
    f_r = d.final.effects["platen_resonator"]["f_r"]
    assert 2.9 < f_r < 3.3, f_r
    if part == "first":  # the specimen softens: in the model, or said with what it would give
        # (2026-12-06, these 100 s: specimen_degradation 22 % -> 17 %, not added: its
        # exponent 1.94 is charged for its distance from Baber & Noori's 1; on the run's
        # first 82 s it ends at its bound, 2)
        missed = [f for f in d.findings if f["kind"] == "not_added"
                  and f["what"].startswith("specimen_degradation ")]
        assert "specimen_degradation" in d.final_effects or (
            missed and missed[0]["numbers"]["error_after"]
            < missed[0]["numbers"]["error_before"] - 0.02), d.findings
