"""A command column that is not the command the table followed
(`vtable.diagnose.command_check`): runs of the independent truth simulator (tests/truth) on
LNEC's table, their h_span column moved by whole samples after the fact, as a drive logged
on another clock would be, or scaled, as a column in another unit or of a miscalibrated
span would be."""

from __future__ import annotations

import dataclasses
import functools
import tempfile
from pathlib import Path

import numpy as np
import pytest
import truth

from vtable.diagnose.engine import Diagnoser
from vtable.runs import read_run, write_run

SHIFT = 8  # samples at 200 Hz: 40 ms


@functools.cache
def pink_run(fs: float = 200.0) -> str:
    """LNEC's bare table, pink noise 0.5-25 Hz, 30 s at 0.5 in; 1 % noise."""
    folder = Path(tempfile.mkdtemp(prefix="vtable-offset-"))
    cmd = truth.random_command(30.0, (0.5, 25.0), peak_in=0.5, seed=11, pink=True)
    res = truth.simulate(truth.lnec_table(), truth.none(), cmd, fs=fs)
    return str(truth.write_run(folder / "pink", res, truth.none(), noise=0.01, seed=11)[0])


def moved(k: int, fs: float = 200.0) -> str:
    """The run with its command column `k` samples late (k > 0) or early, the end value
    held where the column runs out."""
    run = read_run(pink_run(fs))
    x = run.channels["h_span"]
    x = np.concatenate([np.full(k, x[0]), x[:-k]]) if k > 0 else \
        np.concatenate([x[-k:], np.full(-k, x[-1])])
    out = dataclasses.replace(run, channels={**run.channels, "h_span": x},
                              name=f"pink_{'late' if k > 0 else 'early'}")
    stem = Path(pink_run(fs)).with_name(out.name)
    write_run(out, stem)
    return str(stem.with_suffix(".toml"))


@pytest.mark.parametrize("k, fs", [(SHIFT, 200.0), (-SHIFT, 200.0), (2 * SHIFT, 400.0)])
def test_a_command_column_out_of_time_is_found_and_said(k, fs):
    """Moved by 40 ms either way, the starting model loses to the black box (the servo
    loop cannot be a pure delay); the lag is estimated within a sample of the analysis
    rate (200 Hz) and the starting model refitted on the command moved back gains at least
    a fifth of its error; the finding names the lag and the shift that undoes it, in the
    run file's samples (at 400 Hz, twice the analysis rate's)."""
    d = Diagnoser([read_run(moved(k, fs))], catalog=["valve_dynamics"]).diagnose()
    said = [f for f in d.findings if f["kind"] == "command_offset"]
    assert len(said) == 1, [f["kind"] for f in d.findings]
    n = said[0]["numbers"]
    assert n["samples"] == pytest.approx(k, abs=fs / 200.0), n
    assert n["offset_s"] == pytest.approx(k / fs, abs=1.5 / 200.0), n
    assert n["error_after"] <= 0.8 * n["error_before"], n
    assert ("lags" if k > 0 else "leads") in said[0]["what"]
    assert f"shift the h_span column by {n['samples']:+d} samples" in said[0]["action"]


def test_a_drive_files_offset_and_scale_are_said_as_the_ones_to_give():
    from vtable.diagnose.command_check import CommandOffset, CommandScale

    c = CommandOffset("r", 0.0405, 0.0008, 200.0, 8, 0.8, 0.4, 0.2, drive_offset=0.1)
    assert "drive_offset_s = 0.14 (now 0.1)" in c.action() and "command lags" in c.text()
    auto = dataclasses.replace(c, drive_offset="auto").action()
    assert "the lag the reader's note gives +0.04 s" in auto
    s = CommandScale("r", 0.5, 0.001, 0.3, 0.02, 0.02, drive_scale=2.0)
    assert "drive_scale = 1 (now 2)" in s.action() and "reads 2 x" in s.text()
    assert "correct it (x 0.5)" in CommandScale("r", 0.5, 0.001, 0.3, 0.02, 0.02).action()


@pytest.mark.parametrize("lag, gain", [(5, None), (0, 1.2)])
def test_an_aligned_run_and_a_lag_or_scale_that_buys_nothing_are_not_said(
        monkeypatch, lag, gain):
    """The run as the truth wrote it: its final model beats the black box, nothing is
    tested. Made to lose (the black box's errors halved), a lag or a DC gain the estimate
    gives where there is none (forced to 5 samples, or to 1.2) is tried: the starting model
    is refitted with it and, gaining nothing, it is not said."""
    import vtable.diagnose.command_check as check
    from vtable.ident.drive import estimate_offset

    run = read_run(pink_run())
    d = Diagnoser([run], catalog=["valve_dynamics"]).diagnose()
    assert not [f for f in d.findings if f["kind"].startswith("command_")]
    assert d.final_error < d.limits.reference

    def false(*a, **kw):
        est = estimate_offset(*a, **kw)
        if gain is not None:
            dc = dataclasses.replace(est.structure.dc_gain, params={"gain": gain},
                                     stderr={"gain": 1e-3})
            est = dataclasses.replace(est, structure=dataclasses.replace(est.structure,
                                                                         dc_gain=dc))
        return dataclasses.replace(est, offset=lag / 200.0, stderr=1e-4)

    losing = dataclasses.replace(d.limits, groups=tuple(
        dataclasses.replace(g, reference=0.5 * g.error) for g in d.limits.groups))
    monkeypatch.setattr(check, "estimate_offset", false)
    refits = []
    diagnoser = Diagnoser([run], catalog=["valve_dynamics"])
    model = diagnoser.model
    monkeypatch.setattr(diagnoser, "model", lambda *a, **kw: refits.append(1) or model(*a, **kw))
    tried = []
    found = check.command_checks(diagnoser, dataclasses.replace(d, limits=losing), tried.append)
    assert tried and refits == [1] and found == []


@pytest.mark.parametrize("scale", [1.1, 0.5, 1 / 25.4, 25.4])
def test_a_command_column_out_of_scale_is_found_and_said(scale):
    """The column 10 % too large, half what was played, in inches read as mm (1/25.4 of the
    command) or the other way round: the starting model loses to the black box; the
    table's DC gain over the column (a valve-integrator loop's is 1) gives the scale within
    1 %, and the starting model refitted on the column rescaled gains at least a fifth;
    the finding gives the factor to correct it by. No lag is said."""
    run = read_run(pink_run())
    out = dataclasses.replace(run, channels={**run.channels,
                                              "h_span": scale * run.channels["h_span"]},
                              name=f"pink_x{round(scale * 1000)}")
    stem = Path(pink_run()).with_name(out.name)
    write_run(out, stem)
    d = Diagnoser([read_run(stem.with_suffix(".toml"))], catalog=["valve_dynamics"]).diagnose()
    said = [f for f in d.findings if f["kind"] == "command_scale"]
    assert len(said) == 1 and not [f for f in d.findings if f["kind"] == "command_offset"], \
        [f["kind"] for f in d.findings]
    n = said[0]["numbers"]
    assert n["gain"] == pytest.approx(1 / scale, rel=0.01), n
    assert n["error_after"] <= 0.8 * n["error_before"], n
    assert f"correct it (x {n['gain']:.4g})" in said[0]["action"]


def test_a_column_late_and_out_of_scale_says_both():
    """8 samples late and 10 % too large: the lag found alone (98.5 % -> 4.8 % measured),
    the scale found after it (4.8 % -> 1.0 %: alone it gains nothing against the lag)."""
    run = read_run(pink_run())
    x = run.channels["h_span"]
    x = 1.1 * np.concatenate([np.full(SHIFT, x[0]), x[:-SHIFT]])
    stem = Path(pink_run()).with_name("pink_both")
    write_run(dataclasses.replace(run, channels={**run.channels, "h_span": x},
                                  name="pink_both"), stem)
    d = Diagnoser([read_run(stem.with_suffix(".toml"))], catalog=["valve_dynamics"]).diagnose()
    said = {f["kind"]: f["numbers"] for f in d.findings if f["kind"].startswith("command_")}
    assert set(said) == {"command_offset", "command_scale"}, said
    lag, scale = said["command_offset"], said["command_scale"]
    assert lag["samples"] == SHIFT and scale["gain"] == pytest.approx(1 / 1.1, rel=0.01)
    assert scale["error_before"] == pytest.approx(lag["error_after"], rel=1e-9)
    assert scale["error_after"] < 2 * d.noise_floor < lag["error_after"], (lag, scale)
