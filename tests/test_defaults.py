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
    code = main(["simulate", "--table", "lnec-st1d", "--specimen", "none", "--peak", "0.25",
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
