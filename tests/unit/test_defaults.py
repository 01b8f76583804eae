"""Defaults that fit the table (issue 18, deliverable 8): `simulate --table T` with no
other arguments runs within the table's payload and limits and says what it chose; a
metric run's quantities are shown in mm, m/s², kN."""

import numpy as np
import pytest

from vtable.cli import main


def test_simulate_lnec_with_the_defaults_runs_and_says_what_it_chose(capsys):
    code = main(["simulate", "--table", "lnec-st1d"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert ("specimen: none, the bare table (the SDOF frame's 31026 kg exceeds lnec-st1d's "
            "payload of 5000 kg; --specimen chooses one)") in out
    assert "peak 2.01 mm: 80% of lnec-st1d's acceleration limit" in out
    assert "beyond the table's" not in out  # the default band is within the table's
    assert " mm\n" in out and " in\n" not in out and " kN\n" in out  # the metric peak table


def test_default_command_is_within_the_tables_limits():
    from vtable.signals import make_command
    from vtable.sim.experiment import load_table
    from vtable.verbs.simulation import command_peaks, fit_peak

    lab = load_table("lnec-st1d")
    cmd, _why = fit_peak(lab, "random", lambda p: make_command("random", peak_in=p), "metric")
    x, v, a = command_peaks(cmd)
    assert v <= 0.8 * lab.velocity + 1e-12 and v == pytest.approx(0.164, abs=0.002)
    assert a == pytest.approx(0.8 * lab.acceleration, rel=1e-6)  # 20 m/s²: the binding one
    assert x <= 0.5 * lab.stroke and x == pytest.approx(2.01e-3, rel=0.01)
    # the 0.25 in default asks 0.52 m/s (20 in/s) of a 0.40 m/s table
    _x0, v0, _ = command_peaks(make_command("random", peak_in=0.25))
    assert v0 == pytest.approx(0.519, abs=0.002) and v0 > lab.velocity


def test_an_explicit_peak_beyond_a_limit_is_refused(capsys):
    code = main(["simulate", "--table", "lnec-st1d", "--specimen", "none", "--peak", "0.25in",
                 "--duration", "1"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "velocity limit" in err


def test_an_explicit_specimen_beyond_the_payload_is_refused(capsys):
    code = main(["simulate", "--table", "lnec-st1d", "--specimen", "sdof_frame"])
    err = capsys.readouterr().err
    assert code == 2 and "above the table's capacity of 11.0231 kips" in err


def test_a_metric_runs_amplitudes_are_in_mm_not_mil():
    from vtable.diagnose.prose import localisation_text
    from vtable.diagnose.statistics import Comparison
    from vtable.display import run_family
    from vtable.runs.model import Run

    t = np.arange(0.0, 1.0, 0.01)
    metric = Run(name="r", time=t, channels={"h_span": 0 * t}, units={"h_span": "mm"}, meta={})
    imperial = Run(name="r", time=t, channels={"h_span": 0 * t}, units={"h_span": "in"}, meta={})
    assert run_family(metric) == "metric" and run_family(imperial) == "imperial"
    c = Comparison(0.05, {"a": {"table acceleration": 0.02}, "b": {"table acceleration": 0.08}},
                   0.01, amplitude=[("a", 0.762e-3, 0.02), ("b", 1.524e-3, 0.08)],
                   display="metric")
    text = localisation_text(c)
    assert "2.0% at 0.762 mm rms, 8.0% at 1.52 mm rms" in text and "mil" not in text


def test_amplitudes_take_a_unit_and_a_metric_run_stores_metric_keys(tmp_path, capsys):
    """`--peak 2mm` (or 0.002m, 0.0787in) on LNEC's metric table is a 2 mm peak command,
    and its run file says `peak_mm = 2.0`; a bare number is in the table's unit (mm there,
    in on the report's table); a unit that is not a length is one line naming --peak
    (issue 33: the flag was inches whatever the table, the file `peak_in`)."""
    import tomllib

    from vtable.runs import read_run

    peaks = {}
    for k, text in enumerate(("2mm", "0.002m", "0.0787402in", "2")):
        stem = tmp_path / f"r{k}"
        code = main(["simulate", "--table", "lnec-st1d", "--specimen", "none", "--peak", text,
                     "--duration", "2", "--out", str(stem)])
        out, err = capsys.readouterr()
        assert code == 0, err
        command = tomllib.loads(stem.with_suffix(".toml").read_text())["command"]
        assert command["peak_mm"] == pytest.approx(2.0, rel=1e-6) and "peak_in" not in command
        peaks[text] = np.max(np.abs(read_run(stem.with_suffix(".toml")).channel("h_span")))
        assert "--peak sets it" not in out  # given, not chosen
    # one command (m), a 2 mm peak seen through the run's 200 Hz samples (1.96 mm)
    assert all(p == pytest.approx(peaks["2mm"], rel=1e-5) for p in peaks.values()), peaks
    assert peaks["2mm"] == pytest.approx(0.002, rel=0.03)
    code = main(["simulate", "--specimen", "none", "--peak", "0.1", "--duration", "2",
                 "--out", str(tmp_path / "eerc")])
    assert code == 0
    command = tomllib.loads((tmp_path / "eerc.toml").read_text())["command"]
    assert command["peak_in"] == pytest.approx(0.1) and "peak_mm" not in command
    capsys.readouterr()
    for bad, msg in (("3furlongs", "'furlongs'"), ("2g", "not a length unit"),
                     ("two", "is not a length")):
        code = main(["simulate", "--peak", bad])
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1 and "--peak" in err and msg in err, err


def test_a_run_file_gives_its_peak_in_one_unit(tmp_path):
    from vtable.errors import VtableError
    from vtable.runs.format import command_from_dict

    assert command_from_dict({"peak_mm": 2.0}, "r.toml [command]").peak == pytest.approx(0.002)
    assert command_from_dict({"peak_in": 1.0}, "r.toml [command]").peak == pytest.approx(0.0254)
    with pytest.raises(VtableError, match="peak_in and peak_mm both give"):
        command_from_dict({"peak_in": 1.0, "peak_mm": 25.4}, "r.toml [command]")


def test_the_drives_target_peak_takes_a_unit(monkeypatch):
    """`vtable drive --target-peak 50mm` reaches the verb as 50 mm in --target-unit's
    terms (1.9685 in), a bare number in --target-unit."""
    from vtable import cli, verbs

    seen = {}

    def drive(*args, **kw):
        seen["peak"] = args[13]
        raise SystemExit(0)

    monkeypatch.setattr(verbs, "drive", drive)
    for argv, want in ((["--target-peak", "50mm"], 50 / 25.4),
                       (["--target-peak", "2"], 2.0),
                       (["--target-peak", "50mm", "--target-unit", "mm"], 50.0)):
        a = cli.parser().parse_args(["drive", "r.toml", "--target", "elcentro", "--out", "d",
                                     *argv])
        with pytest.raises(SystemExit):
            cli.cmd_drive(a)
        assert seen["peak"] == pytest.approx(want), argv
