"""A run's display units follow its [units] (issue 18, deliverable 8): a simulated run on
a metric table is written in mm, mm/s, g (LNEC's convention) and kN and reads back to the
same SI values; the verbs print a metric run's quantities in mm, kN, kN/mm (compare,
identify, simulate) and an EERC run's in mil, in, kip; the JSON stays as it was.

The campaigns are the truth simulator's (tests/truth: LNEC's table written in SI, EERC's in
in/g/kip), 10 s at 200 Hz, two amplitudes each; the numbers printed are checked against
the data (RMS of h_span) and the JSON (kip, kip/in) with conversion factors written out
here: 1 in = 25.4 mm, 1 kip = 4.4482216152605 kN.
"""

from __future__ import annotations

import functools
import json
import re
import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parents[1]))
import real_data
import truth

from vtable import display
from vtable.cli import main
from vtable.runs import read_run, write_run

KN_PER_KIP = 4.4482216152605
MM_PER_IN = 25.4
FS = 200.0


@functools.cache
def campaign(table: str) -> list[Path]:
    """Two 10 s random runs (0.03 and 0.08 in RMS) on the truth's `table` with 0.3 kip
    (LNEC) or 2 kip (EERC) of actuator friction, 0.5 % sensor noise."""
    folder = Path(tempfile.mkdtemp(prefix=f"display_{table}_"))
    tab = (truth.lnec_table(effects={"actuator_friction": {"friction": 0.3}}) if table == "lnec"
           else truth.eerc_table(effects={"actuator_friction": {"friction": 2.0}}))
    paths = []
    for k, rms in enumerate((0.03, 0.08)):
        res = truth.simulate(tab, truth.none(),
                             truth.random_command(10.0, (0.0, 25.0), rms_in=rms, seed=k), fs=FS)
        paths.append(truth.write_run(folder / f"r{k}", res, declared=truth.none(),
                                     noise=0.005, seed=k)[0])
    return paths


def _cli(capsys, *argv) -> str:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 0, err
    return out


def _rms(path: Path) -> float:
    x = read_run(path).channel("h_span")
    return float(np.sqrt(np.mean(x**2)))


# ---- writing: a metric table's run in mm, g, kN, read back identically -------------------
def test_simulate_on_a_metric_table_writes_its_run_in_mm_g_kn(tmp_path, capsys):
    out = _cli(capsys, "simulate", "--table", "lnec-st1d", "--duration", "2",
               "--out", tmp_path / "m")
    declared = tomllib.loads((tmp_path / "m.toml").read_text())["units"]
    assert {k: declared[k] for k in ("h_span", "avg_hdisp", "h1_disp", "h_vel", "avg_hacc",
                                     "acc_cmd", "h1_force")} == {
        "h_span": "mm", "avg_hdisp": "mm", "h1_disp": "mm", "h_vel": "mm/s", "avg_hacc": "g",
        "acc_cmd": "g", "h1_force": "kN"}
    raw = np.genfromtxt(tmp_path / "m.csv", delimiter=",", names=True)
    run = read_run(tmp_path / "m.toml")
    np.testing.assert_allclose(run.channel("h_span"), raw["h_span"] / 1000, rtol=1e-15)
    np.testing.assert_allclose(run.channel("h1_force"), raw["h1_force"] * 1000, rtol=1e-15)
    np.testing.assert_allclose(run.channel("avg_hacc"), raw["avg_hacc"] * 9.80665, rtol=1e-15)
    # the peak table is the file's values, in the file's units
    for ch, unit in (("h_span", "mm"), ("avg_hdisp", "mm"), ("h1_force", "kN")):
        peak = float(np.max(np.abs(raw[ch])))
        assert re.search(rf"^  {ch} +{re.escape(f'{peak:.4g}')} {unit}$", out, re.M), out
    assert " in\n" not in out and "kip" not in out and "mil" not in out


def test_a_metric_run_reads_back_to_the_same_si_values(tmp_path):
    from vtable.params.specimen import NoSpecimen
    from vtable.signals import make_command
    from vtable.sim.experiment import load_table, run_experiment

    lab = load_table("lnec-st1d")
    exp = run_experiment(NoSpecimen(), make_command("random", duration=1.0, peak_in=0.04),
                         vt=lab)
    run = exp.run
    run.units = display.file_units(run.units, display.table_family(lab))
    assert run.units["avg_hdisp"] == "mm" and run.units["h1_force"] == "kN"
    write_run(run, tmp_path / "r")
    back = read_run(tmp_path / "r.toml")
    assert back.units == run.units and display.run_family(back) == "metric"
    for k, v in run.channels.items():
        np.testing.assert_allclose(back.channels[k], v, rtol=1e-12, atol=0, err_msg=k)
    assert np.array_equal(back.time, run.time)


def test_an_eerc_run_keeps_the_formats_units(tmp_path, capsys):
    out = _cli(capsys, "simulate", "--specimen", "none", "--duration", "1",
               "--out", tmp_path / "e")
    meta = tomllib.loads((tmp_path / "e.toml").read_text())
    assert not {"h_span", "avg_hdisp", "h1_force", "avg_hacc"} & set(meta.get("units", {}))
    raw = np.genfromtxt(tmp_path / "e.csv", delimiter=",", names=True)
    peak = float(np.max(np.abs(raw["h1_force"])))  # kip, the format's unit
    assert re.search(rf"^  h1_force +{re.escape(f'{peak:.4g}')} kip$", out, re.M), out
    assert " mm\n" not in out and " kN\n" not in out


# ---- the verbs' printed output ----------------------------------------------------------
def _amplitudes(out: str, unit: str) -> list[str]:
    line = next(s for s in out.splitlines() if s.strip().startswith("where:"))
    return re.findall(rf"at ([\d.]+) {unit} rms", line.split("by command amplitude:")[1]
                      .split(";")[0])


def test_compare_shows_a_metric_campaign_in_mm_and_kn(tmp_path, capsys):
    runs = campaign("lnec")
    out = _cli(capsys, "compare", *runs, "--with", "actuator_friction",
               "--json", tmp_path / "c.json")
    assert _amplitudes(out, "mm") == [f"{1000 * _rms(p):.3g}" for p in runs]
    friction_kip = json.loads((tmp_path / "c.json").read_text())["params"][
        "actuator_friction"]["friction"]  # the JSON keeps the effect's unit
    assert f"actuator_friction: friction = {friction_kip * KN_PER_KIP:.4g} kN" in out
    assert not re.search(r"\b(mil|kip)\b", out)


def test_compare_shows_an_eerc_campaign_in_mil_and_kip(tmp_path, capsys):
    runs = campaign("eerc")
    out = _cli(capsys, "compare", *runs, "--with", "actuator_friction",
               "--json", tmp_path / "c.json")
    mils = [1000 * (1000 * _rms(p) / MM_PER_IN) for p in runs]  # m -> mm -> in -> mil
    assert _amplitudes(out, "mil") == [f"{m:.0f}" if m >= 10 else f"{m:.2g}" for m in mils]
    friction = json.loads((tmp_path / "c.json").read_text())["params"]["actuator_friction"][
        "friction"]
    assert f"actuator_friction: friction = {friction:.4g} kip" in out
    assert " mm " not in out and "kN" not in out


def test_identify_shows_a_metric_runs_springs_in_kn_per_mm(tmp_path, capsys):
    run = campaign("lnec")[1]
    out = _cli(capsys, "identify", run, "--json", tmp_path / "i.json")
    hs = json.loads((tmp_path / "i.json").read_text())["runs"][0]["horizontal_spring"]
    kn_per_mm = KN_PER_KIP / MM_PER_IN  # 1 kip/in
    kn_s_per_m = KN_PER_KIP / 1000 / (MM_PER_IN / 1000)  # 1 lb-s/in
    ks = ", ".join(f"{k * kn_per_mm:.3g}" for k in hs["k_h_kip_per_in"])
    cs = ", ".join(f"{c * kn_s_per_m:.3g}" for c in hs["c_h_lb_s_per_in"])
    assert f"k_h {ks} kN/mm, c_h {cs} kN-s/m" in out
    assert not re.search(r"\bkip\b", out) and "lb-s/in" not in out
    out_e = _cli(capsys, "identify", campaign("eerc")[1])
    assert "kip/in" in out_e and "lb-s/in" in out_e and "kN" not in out_e


def test_a_metric_tables_refusal_is_in_its_units(capsys):
    code = main(["simulate", "--table", "lnec-st1d", "--specimen", "none", "--peak", "0.25in",
                 "--duration", "1"])
    err = capsys.readouterr().err
    m = re.search(r"velocity reaches ([\d.]+) mm/s \(first beyond ±([\d.]+) mm/s", err)
    assert code == 2 and m, err
    assert float(m.group(2)) == 400.0  # the preset's 0.40 m/s
    # the same command's peak velocity, from its samples, as the simulator checks it
    from vtable.signals import make_command
    from vtable.verbs.simulation import command_peaks
    v = command_peaks(make_command("random", duration=1.0, peak_in=0.25, band=(0.0, 25.0)))[1]
    assert m.group(1) == f"{1000 * v:.1f}"


# ---- the one place: display -------------------------------------------------------------
def test_the_display_conversions():
    from vtable.diagnose.result import params_text
    from vtable.sim.simulator import Exceedance
    from vtable.verbs.simulation import exceedance_text

    assert params_text("actuator_friction", {"friction": 3.0}, "metric") == \
        f"friction = {3 * KN_PER_KIP:.4g} kN"
    assert params_text("actuator_friction", {"friction": 3.0}, "imperial") == "friction = 3 kip"
    lb_in = KN_PER_KIP / 1000 * MM_PER_IN / 1000  # kN-m per lb-in
    assert params_text("pitch_flexibility", {"k_theta": 2e10, "c_theta": 3e7}, "metric") == (
        f"k_theta = {2e10 * lb_in:.4g} kN-m/rad, c_theta = {3e7 * lb_in:.4g} kN-m-s/rad")
    e = Exceedance("H1", "velocity", 0.1, 0.5, 0.4)
    assert exceedance_text(e, "metric") == "H1 velocity 500 mm/s exceeds 400 mm/s from t = 0.100 s"
    assert exceedance_text(e, "imperial") == str(e)
    # accelerations: as the run declares them (LNEC's g), else m/s²
    assert display.unit_for("g", "metric", ["mm", "g", "kN"]) == "g"
    assert display.unit_for("g", "metric", ["m", "m/s2", "N"]) == "m/s2"
    assert display.unit_for("g", "imperial", ["m/s2"]) == "g"
    assert display.amplitude(0.762e-3, "metric") == "0.762 mm"
    assert display.amplitude(0.762e-3) == "30 mil"


@real_data.NEEDED
def test_lnecs_measured_run_is_shown_in_its_units(tmp_path, capsys):
    run = read_run(real_data.copy_run(tmp_path))
    assert display.run_family(run) == "metric"
    assert display.family(run.units.values()) == "metric"  # mm and g: g is neither family's
    assert display.unit_for("g", "metric", run.units.values()) == "g"  # the lab's own
    # a simulated run on its table is written in the lab's units
    assert display.file_units({"avg_hacc": "g", "avg_hdisp": "in"}, "metric") == {
        k: run.units[k] for k in ("avg_hacc", "avg_hdisp")}
    out = _cli(capsys, "identify", tmp_path / "lnec_pink_2.toml", "--json", tmp_path / "i.json")
    hs = json.loads((tmp_path / "i.json").read_text())["runs"][0]["horizontal_spring"]
    ks = ", ".join(f"{k * KN_PER_KIP / MM_PER_IN:.3g}" for k in hs["k_h_kip_per_in"])
    assert f"k_h {ks} kN/mm" in out and not re.search(r"\bkip\b", out)


def test_the_diagnosis_reports_axes_follow_the_runs_units(tmp_path, capsys):
    """The HTML report's Bode plots: a metric run written by `simulate` (mm, g, kN) per mm
    in its own units; the magnitude is 20 log10 of the SI ratio in those units."""
    from types import SimpleNamespace

    from vtable.ident.structure import lowest_declared_mode
    from vtable.ident.tf import transfer_function
    from vtable.viz.diagnosis_report import bode_frames, tf_overlay

    _cli(capsys, "simulate", "--table", "lnec-st1d", "--duration", "4", "--out", tmp_path / "m")
    run = read_run(tmp_path / "m.toml")
    stage = SimpleNamespace(predictions={run.name: run.channels})  # the model = the data
    d = SimpleNamespace(runs=[run], stages=[stage, stage])
    for group, label, scale in (("table acceleration", "g/mm", 1 / 9.80665 / 1000),
                                ("actuator force", "kN/mm", 1e-3 / 1000),
                                ("table displacement", "mm/mm", 1.0)):
        fig = tf_overlay(d, group)
        assert fig.axes[0].get_ylabel() == f"magnitude (dB re 1 {label})"
        y = {"table acceleration": "avg_hacc", "actuator force": "h1_force",
             "table displacement": "avg_hdisp"}[group]
        line = fig.axes[0].get_lines()[-1]  # the measured trace, drawn last
        n = bode_frames(len(run.time), run.fs, lowest_declared_mode(run))
        tm = transfer_function(run.channel("h_span"), run.channel(y), run.fs, n)
        sel = (tm.f >= 2 * tm.resolution_hz) & (tm.f <= min(30.0, 0.4 * run.fs))
        # drawn where coherence and the command's power support it (viz.figures.supported),
        # and there exactly the H1 in the run's units
        drawn = np.isfinite(line.get_ydata())
        assert drawn.mean() > 0.5, drawn.mean()
        np.testing.assert_allclose(line.get_ydata()[drawn],
                                   20 * np.log10(scale * np.abs(tm.H[sel]))[drawn], rtol=1e-12)
