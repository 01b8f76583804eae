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


def test_a_drive_files_offset_is_said_as_the_one_to_give():
    from vtable.diagnose.command_check import CommandOffset

    c = CommandOffset("r", 0.0405, 0.0008, 200.0, 8, 0.8, 0.4, 0.2, drive_offset=0.1)
    assert "drive_offset_s = 0.14 (now 0.1)" in c.action() and "command lags" in c.text()


def test_an_aligned_run_and_a_lag_that_buys_nothing_are_not_said(monkeypatch):
    """The run as the truth wrote it: no finding. A lag the estimate gives where there is
    none (forced to 5 samples here, the DC gain as measured: 1) is tried and, the refit
    gaining nothing, not said."""
    import vtable.diagnose.command_check as check
    from vtable.ident.drive import estimate_offset

    run = read_run(pink_run())
    d = Diagnoser([run], catalog=["valve_dynamics"]).diagnose()
    assert not [f for f in d.findings if f["kind"].startswith("command_")]
    assert d.final_error < d.limits.reference

    def false_lag(*a, **kw):
        return dataclasses.replace(estimate_offset(*a, **kw), offset=5 / 200.0, stderr=1e-4)

    losing = dataclasses.replace(d.limits, groups=tuple(
        dataclasses.replace(g, reference=0.5 * g.error) for g in d.limits.groups))
    monkeypatch.setattr(check, "estimate_offset", false_lag)
    tried = []
    found = check.command_checks(Diagnoser([run], catalog=["valve_dynamics"]),
                                 dataclasses.replace(d, limits=losing), tried.append)
    assert tried and found == []


@pytest.mark.parametrize("scale", [1.1, 0.5, 1 / 25.4])
def test_a_command_column_out_of_scale_is_found_and_said(scale):
    """The column 10 % too large, half what was played, or in mm read as inches (1/25.4 of
    the command in the file's inches): the starting model loses to the black box; the
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
