"""Rough edges of `vtable simulate` a new user hit (issue 33, item 3): a cut earthquake
shakes as the whole record does, and amplitudes take a unit, a metric table's run saying
and storing its peak in mm."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from vtable.cli import main

YIELDING = str(Path(__file__).resolve().parents[2] / "examples" / "yielding_frame.toml")
G = 9.80665
INCH = 0.0254


def _acc(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.gradient(np.gradient(x, t), t)


def test_a_cut_earthquake_is_the_whole_records_first_seconds():
    """`--duration 15` (and 5) on El Centro at `--peak 2`: the whole processed record
    scaled to 2 in, its first seconds. Before the cut's last 2 s (where it is brought to
    rest) the displacement is the whole's to 1e-9 m; the peaks over the cut are the whole's
    over the same seconds, 2.00 in and 1.03 g, to 0.5 % (the cut holds the whole's peaks,
    both in its first 3 s). The cut scaled to 2 in on its own gave 0.49 g (15 s) and
    0.84 g (5 s); integrated on its own and scaled as the whole, 1.03 g but 4.21 in over
    15 s and 2.45 in over 5 s."""
    from vtable.signals import make_command

    whole = make_command("earthquake", record="elcentro", peak_in=2.0)
    for seconds in (15.0, 5.0):
        cut = make_command("earthquake", record="elcentro", peak_in=2.0, duration=seconds)
        n = len(cut.t)
        assert cut.t[-1] == pytest.approx(seconds, abs=0.01)
        np.testing.assert_allclose(cut.t, whole.t[:n])
        before = cut.t < seconds - 2.05  # the rest 2 s plus one processed step (5.5 ms)
        assert np.max(np.abs(cut.x[before] - whole.x[:n][before])) < 1e-9
        assert np.max(np.abs(cut.x)) / INCH == pytest.approx(2.0, rel=0.005)
        assert np.max(np.abs(whole.x[:n])) / INCH == pytest.approx(2.0, rel=0.005)
        a_cut, a_whole = _acc(cut.t, cut.x), _acc(whole.t, whole.x)[:n]
        assert np.max(np.abs(a_cut)) / G == pytest.approx(1.03, abs=0.005)
        assert np.max(np.abs(a_cut)) == pytest.approx(np.max(np.abs(a_whole)), rel=0.005)
        # at rest at its end (the whole moves there: 0.685 in and 0.05 m/s at 15 s)
        v = np.gradient(cut.x, cut.t)
        assert abs(cut.x[-1]) < 1e-5 and abs(v[-1]) < 5e-3, (cut.x[-1], v[-1])
        assert cut.table["peak_in"] == pytest.approx(2.0)  # the whole record's peak
        assert "(the whole reaches ±2 in, this part's own 2 in)" in cut.notes[-1], cut.notes


def test_the_yielding_frame_cut_feels_what_the_whole_record_gives_it(capsys, tmp_path):
    """The issue's run: the yielding frame under El Centro at `--peak 2`, its first 15 s
    and the whole record. The cut's command is the whole's until 13 s, after the frame's
    peaks: the same peak drift (0.750 in, 2.50 x the yield drift), table acceleration
    (0.288 g) and command (2 in), to 0.5 %. Before: 1.28 x at 0.154 g (the cut scaled to
    2 in on its own), then 2.49 x but a 4.21 in command."""
    out = {}
    for name, extra in (("cut", ["--duration", "15"]), ("whole", [])):
        code = main(["simulate", "--specimen", YIELDING, "--command", "earthquake",
                     "--record", "elcentro", "--peak", "2", *extra, "--json",
                     str(tmp_path / f"{name}.json")])
        _, err = capsys.readouterr()
        assert code == 0, err
        out[name] = json.loads((tmp_path / f"{name}.json").read_text())
    cut, whole = out["cut"], out["whole"]
    assert cut["duration_s"] == pytest.approx(15.0, abs=0.01)
    assert whole["duration_s"] == pytest.approx(22.05, abs=0.01)
    for ch, want in (("floor1_drift", 0.750), ("acc_n_ne", 0.288), ("h_span", 2.0)):
        assert cut["peaks"][ch]["peak"] == pytest.approx(whole["peaks"][ch]["peak"],
                                                         rel=0.005), ch
        assert cut["peaks"][ch]["peak"] == pytest.approx(want, rel=0.01), ch
    assert "storey 1: peak drift 2.50 x its yield drift (it yielded)" in cut["notes"]


def test_a_metric_tables_peak_takes_a_unit_and_is_said_and_stored_in_mm(capsys, tmp_path):
    """On LNEC's metric table `--peak 20mm`, `0.02m`, `0.787402in` and a bare `20` (mm
    there) are one 20 mm earthquake command: the run file's [command] holds
    `peak_mm = 20.0` (no `peak_in`), its h_span peaks at 20 mm, and the notes say ±20 mm,
    not 0.787 in. The file reads back as 20 mm; with `peak_in` beside `peak_mm` it is one
    line naming both, exit 2."""
    from vtable.runs import read_run

    peaks = {}
    for k, text in enumerate(("20mm", "0.02m", "0.787402in", "20")):
        stem = tmp_path / f"r{k}"
        code = main(["simulate", "--table", "lnec-st1d", "--specimen", "none", "--command",
                     "earthquake", "--duration", "5", "--peak", text, "--out", str(stem)])
        out, err = capsys.readouterr()
        assert code == 0, err
        command = tomllib.loads(stem.with_suffix(".toml").read_text())["command"]
        assert command["peak_mm"] == pytest.approx(20.0, rel=1e-5) and "peak_in" not in command
        assert "scaled to ±20 mm peak" in out and "this part's own 20 mm" in out, out
        assert " in peak" not in out and " in," not in out
        run = read_run(stem.with_suffix(".toml"))
        assert run.units["h_span"] == "mm"
        peaks[text] = float(np.max(np.abs(run.channel("h_span"))))  # SI, m
    assert all(p == pytest.approx(0.020, rel=0.005) for p in peaks.values()), peaks

    text = (tmp_path / "r0.toml").read_text()
    both = tmp_path / "both.toml"
    both.write_text(text.replace("peak_mm = 20.0", "peak_mm = 20.0\npeak_in = 0.787402"))
    (tmp_path / "both.csv").write_bytes((tmp_path / "r0.csv").read_bytes())
    assert read_run(tmp_path / "r0.toml").drive().peak == pytest.approx(0.020)  # m
    code = main(["tf", str(both)])
    _, err = capsys.readouterr()
    assert code == 2 and err.count("\n") == 1, err
    assert "both.toml" in err and "peak_in and peak_mm" in err, err


def test_a_fitted_cut_says_its_own_peak(capsys):
    """`simulate --table lnec-st1d --command earthquake --duration 3` with no --peak: the
    first 3 s reach 50 mm, half the table's stroke, while the whole record is scaled to
    48 mm; the chosen-peak line says both (it said 'peak 40.8 mm: 50 % of the stroke' of
    a 50 mm command), in mm."""
    code = main(["simulate", "--table", "lnec-st1d", "--specimen", "none", "--command",
                 "earthquake", "--duration", "3", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    d = json.loads(out)
    assert d["peaks"]["h_span"]["peak"] * INCH == pytest.approx(0.050, rel=0.01)
    [line] = [c for c in d["chosen"] if "stroke limit" in c]
    assert line.startswith("peak 48 mm, this part's own 50 mm: 50% of lnec-st1d's stroke")
    assert "a bare number is in mm" in line


@pytest.mark.parametrize("argv, says", [
    (["--peak", "3furlongs"], "'furlongs' is an unknown unit, not a length unit"),
    (["--peak", "0.3g"], "'g' is an acceleration unit, not a length unit"),
    (["--peak", "2.9m/s2"], "'m/s2' is an acceleration unit, not a length unit"),
    (["--peak", "0mm"], "'0mm': a peak displacement must be > 0"),
    (["--peak=-2mm"], "'-2mm': a peak displacement must be > 0"),
    (["--peak", "two"], "'two' is not a length"),
])
def test_a_bad_peak_is_one_line_naming_the_flag(capsys, argv, says):
    code = main(["simulate", "--table", "lnec-st1d", *argv])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "argument --peak:" in err and says in err, err


def test_the_peak_flags_help_names_its_units(capsys):
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "peak command displacement with its unit (2mm, 0.1in, 0.005m)" in text
    assert "a bare number is in the table's unit (in on eerc, mm on a metric table)" in text
