import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from vtable.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_demo_prints_coupled_modes_and_margins(capsys, tmp_path):
    code, out, err = run(capsys, "demo", "--out", str(tmp_path))
    assert code == 0 and err == ""
    assert "2.5402" in out and "8.1876" in out  # Table 9.2: 2.5391, 8.1906 Hz
    assert "gain margin" in out and "phase margin" in out
    assert "virtual table (MuJoCo + servo controllers): El Centro" in out
    assert "effective-motion spectrum ratio" in out
    for f in ("sdof_elcentro.csv", "sdof_elcentro.toml", "sdof_elcentro.rrd"):
        assert (tmp_path / f).is_file()
    code, out, _ = run(capsys, "demo", "--json", "--no-sim")
    d = json.loads(out)
    assert d["modes"][0]["f_hz"] == pytest.approx(2.5391, rel=0.003)
    assert d["x_eff/x_c notch_hz"] == pytest.approx(2.87, abs=0.01)


def test_vtable_entry_point_runs(tmp_path):
    exe = shutil.which("vtable")
    cmd = [exe, "demo"] if exe else [sys.executable, "-m", "vtable.cli", "demo"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "hybrid model" in r.stdout and "peak" in r.stdout
    assert (tmp_path / "vtable-demo" / "sdof_elcentro.rrd").is_file()


def test_simulate_command(capsys, tmp_path):
    code, out, err = run(capsys, "simulate", "--specimen", "concrete_blocks", "--command", "sine",
                         "--freq", "3", "--peak", "0.2", "--duration", "2",
                         "--out", str(tmp_path / "blk"), "--rerun", str(tmp_path / "blk.rrd"),
                         "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["peaks"]["h_span"]["peak"] == pytest.approx(0.2, rel=1e-3)
    assert (tmp_path / "blk.csv").is_file() and (tmp_path / "blk.rrd").is_file()


def test_simulate_noise_is_the_fraction_asked_of_each_measured_channel(capsys, tmp_path):
    """`--noise 0.01`: the noisy run less the noise-free one (same seed) has 1 % of each
    measured channel's RMS, within 10 %; the command is clean; the title says so."""
    from vtable.runs import read_run
    from vtable.runs.model import COMMAND_CHANNELS

    runs = {}
    for noise, name in (("0", "clean"), ("0.01", "noisy")):
        stem = tmp_path / name
        code, _, err = run(capsys, "simulate", "--command", "random", "--peak", "0.1",
                           "--duration", "4", "--seed", "7", "--noise", noise, "--out",
                           str(stem))
        assert code == 0, err
        runs[noise] = read_run(stem.with_suffix(".toml"))
    clean, noisy = runs["0"], runs["0.01"]
    assert set(clean.channels) == set(noisy.channels)
    measured = 0
    for k, v in clean.channels.items():
        d = noisy.channels[k] - v
        if k in COMMAND_CHANNELS or k.startswith("state_"):
            assert not d.any(), k
            continue
        rms = float(np.sqrt(np.mean(v**2)))
        if rms > 0:
            measured += 1
            assert float(np.sqrt(np.mean(d**2))) / rms == pytest.approx(0.01, rel=0.1), k
    assert measured >= 10
    assert "0.01 x RMS white sensor noise (seed 7)" in noisy.meta["title"]
    code, _, err = run(capsys, "simulate", "--noise", "-0.1")
    assert code == 2 and err.count("\n") == 1 and "--noise: expected a fraction" in err


def test_simulate_writes_the_same_columns_whatever_the_effect(capsys, tmp_path):
    """Issue 19: a run's columns do not give its hidden effect away; `--states` adds the
    model's internal states, which do depend on it."""
    from vtable.effects.registry import BUILT_IN

    def header(stem, *extra):
        code, _, err = run(capsys, "simulate", "--command", "random", "--peak", "0.1",
                           "--duration", "1", "--out", str(tmp_path / stem), *extra)
        assert code == 0, err
        return (tmp_path / f"{stem}.csv").read_text().split("\n", 1)[0].split(",")

    bare = header("bare")
    assert not [c for c in bare if c.startswith("state_")]
    for name in BUILT_IN:
        assert header(name, "--effect", name) == bare, name
    friction = header("friction_states", "--effect", "actuator_friction", "--states")
    extra = set(friction) - set(bare)
    assert set(bare) <= set(friction) and "state_q_x" in extra
    assert all(c.startswith("state_") for c in extra)


@pytest.mark.parametrize("args, msg", [
    (["--command", "sine", "--freq", "5", "--peak", "2"], "velocity reaches 62.8 in/s"),
    (["--command", "sine", "--freq", "1", "--peak", "7"], "x command reaches 7.00 in"),
    (["--specimen", "nope"], "unknown specimen preset 'nope'"),
])
def test_simulate_bad_input(capsys, args, msg):
    code, _out, err = run(capsys, "simulate", *args)
    assert code == 2 and msg in err and err.count("\n") == 1


def test_simulate_tall_specimen(capsys, tmp_path):
    p = tmp_path / "tower.toml"
    p.write_text('[specimen]\nkind = "sdof"\nweight_kip = 50.0\nheight_in = 600.0\n'
                 'frequency_hz = 1.0\ndamping = 0.02\n')
    code, _, err = run(capsys, "simulate", "--specimen", str(p))
    assert code == 2 and "overhead clearance (Table 2.2)" in err


def test_export_mjcf(capsys, tmp_path):
    code, _out, _ = run(capsys, "export-mjcf", "--specimen", "sdof_frame", "--out", str(tmp_path))
    assert code == 0 and (tmp_path / "model.xml").is_file()
    assert (tmp_path / "braced_frame.stl").is_file()


def test_export_mjcf_takes_the_table(capsys, tmp_path):
    """`export-mjcf --table` writes that table's platen (issue 19): LNEC's 1975.1 kg
    platen (lnec_st1d.toml) against the EERC slab's 100 kip = 45 359 kg."""
    import mujoco

    masses = {}
    for table in ("lnec-st1d", "eerc"):
        code, _, err = run(capsys, "export-mjcf", "--table", table, "--out",
                           str(tmp_path / table))
        assert code == 0, err
        m = mujoco.MjModel.from_xml_path(str(tmp_path / table / "model.xml"))
        masses[table] = m.body("slab").mass[0]
    assert masses["lnec-st1d"] == pytest.approx(1975.1, rel=1e-4)
    assert masses["eerc"] == pytest.approx(45359.2, rel=1e-4)
    code, _, err = run(capsys, "export-mjcf", "--table", "nowhere", "--out", str(tmp_path))
    assert code == 2 and "nowhere" in err and err.count("\n") == 1


def test_modes_and_margins_json(capsys):
    code, out, _ = run(capsys, "modes", "table9.3", "--json")
    assert code == 0
    assert json.loads(out)["modes"][1]["f_hz"] == pytest.approx(6.71, abs=0.01)
    code, out, _ = run(capsys, "margins", "table7.2:f_o=6", "--json")
    d = json.loads(out)
    assert d["gain_margin"] == pytest.approx(1.63, abs=0.02)
    assert d["phase_margin_deg"] == pytest.approx(19.8, abs=0.5)


def test_tf_table(capsys):
    code, out, _ = run(capsys, "tf", "table6.1:standard", "--fmin", "12.6", "--fmax", "13",
                       "--n", "2", "--json")
    d = json.loads(out)
    assert d["f_hz"][0] == 12.6 and abs(d["phase_deg"][0]) == pytest.approx(180.0, abs=1e-6)
    code, out, _ = run(capsys, "tf", "eerc-sdof", "--out", "theta_h", "--n", "3")
    assert code == 0 and "theta_h/x_c" in out


def test_model_toml_file(capsys, tmp_path):
    p = tmp_path / "frame.toml"
    p.write_text('model = "hybrid"\nheight_in = 219.0\n[specimen]\nkind = "sdof"\n'
                 'weight_kip = 68.0\nheight_in = 219.0\nfrequency_hz = 2.87\ndamping = 0.01\n'
                 '[open_loop]\nf_o_hz = 9.6\nxi_o = 0.606\nk_o_per_s = 29.5\n[rocking]\n'
                 'k_theta_lb_in_per_rad = 2.22e10\nc_theta_lb_in_s_per_rad = 3.7e8\n')
    code, out, _ = run(capsys, "modes", str(p), "--json")
    assert code == 0
    assert json.loads(out)["modes"][0]["f_hz"] == pytest.approx(2.541, abs=0.002)
    q = tmp_path / "override.toml"
    q.write_text('model = "table_sdof"\npreset = "table7.2:standard"\n'
                 '[parameters.open_loop]\nk_o_per_s = 25.07\n')
    code, out, _ = run(capsys, "margins", str(q), "--json")
    assert json.loads(out)["gain_margin"] == pytest.approx(2.99, abs=0.02)  # Table 7.2 k_o=25


@pytest.mark.parametrize("content, msg", [
    ("model = [oops\n", "malformed TOML"),
    ('model = "hybrid"\n[specimen]\nkind = "sdof"\nweight_kip = -68.0\nheight_in = 219.0\n'
     'frequency_hz = 2.87\ndamping = 0.01\n[open_loop]\nf_o_hz = 9.6\nxi_o = 0.606\n'
     'k_o_per_s = 29.5\n[rocking]\nk_theta_lb_in_per_rad = 2.22e10\n'
     'c_theta_lb_in_s_per_rad = 3.7e8\n', "weight_kip must be > 0, got -68"),
    ('model = "spaceship"\n', "model must be one of servo"),
    ('model = "servo"\n[parameters]\nf_o_hz = 9.6\nxi_o = 0.606\n', "missing key 'k_o_per_s'"),
    ('model = "servo"\nbogus = 1\n', "unknown key 'bogus'"),
])
def test_bad_input_is_one_line(capsys, tmp_path, content, msg):
    p = tmp_path / "bad.toml"
    p.write_text(content)
    code, out, err = run(capsys, "modes", str(p))
    assert code == 2 and out == ""
    assert msg in err and err.count("\n") == 1 and "Traceback" not in err
    assert str(p) in err


def test_unknown_preset(capsys):
    code, _, err = run(capsys, "margins", "table6.1:gain=11")
    assert code == 2 and "unknown configuration 'table6.1:gain=11'" in err
    assert err.count("\n") == 1


def test_unstable_configuration_is_reported_with_its_eigenvalues(capsys, tmp_path):
    p = tmp_path / "hot.toml"
    # eq 6.17b: unstable when 2ξ_oω_o < k_o (here 2·0.3·2π·10 = 37.7 < 60)
    p.write_text('model = "servo"\n[parameters]\nf_o_hz = 10.0\nxi_o = 0.3\nk_o_per_s = 60.0\n')
    for cmd in ("margins", "modes", "tf"):
        code, out, err = run(capsys, cmd, str(p))
        assert code == 3 and out == ""
        assert "unstable: eigenvalues with positive real part" in err
        assert err.count("\n") == 1 and "Traceback" not in err


def test_bad_arguments_are_one_line(capsys):
    code, _, err = run(capsys, "tf", "eerc-sdof", "--fmin", "5", "--fmax", "1")
    assert code == 2 and "--fmin < --fmax" in err
    code, _, err = run(capsys, "frobnicate")
    assert code == 2 and err.count("\n") == 1


def test_identify_and_tf_on_runs(capsys, tmp_path, ident_runs):
    sdof = ident_runs["sdof"]
    code, out, err = run(capsys, "identify", str(sdof.source), "--json", str(tmp_path / "id.json"))
    assert code == 0, err
    assert "fixed base" in out and "rocking impedance" in out
    d = json.loads((tmp_path / "id.json").read_text())
    rows = {r["case"]: r for r in d["runs"][0]["table_3_1"]}
    assert rows["fixed base"]["f_hz"] == pytest.approx(2.87, rel=0.01)
    assert d["runs"][0]["rocking_impedance"]["total"]["k_r_lb_in_per_rad"] == pytest.approx(
        2.22e10, rel=0.05)
    code, out, err = run(capsys, "tf", str(sdof.source), "--in", "h_span", "--out", "avg_hdisp",
                         "--fmin", "1", "--fmax", "20", "--png", str(tmp_path / "tf.png"))
    assert code == 0, err
    assert "coherence" in out and (tmp_path / "tf.png").stat().st_size > 10_000
    bare = ident_runs["bare"]
    code, out, err = run(capsys, "identify", str(bare.source), str(sdof.source))
    assert code == 2 and "[specimen] differs" in err


def test_tf_on_a_run_with_a_missing_channel(capsys, tmp_path, ident_runs):
    code, _, err = run(capsys, "tf", str(ident_runs["bare"].source), "--out", "acc_n_ne")
    assert code == 2 and "no channel 'acc_n_ne'" in err


def test_a_verb_returns_a_typed_result_the_cli_only_formats(capsys, tmp_path):
    """python-control's `*_response` pattern: the verb's result carries `to_json()` and
    `report()`; the CLI prints the report, `--json` the JSON, `--json FILE` writes the same
    JSON there and prints the report and the file."""
    from vtable import verbs

    r = verbs.modes("table9.3")
    assert r.modes[1]["f_hz"] == pytest.approx(6.71, abs=0.01)
    _, out, _ = run(capsys, "modes", "table9.3")
    assert out == r.report() + "\n"
    _, out, _ = run(capsys, "modes", "table9.3", "--json")
    assert json.loads(out) == r.to_json()
    f = tmp_path / "m.json"
    code, out, _ = run(capsys, "modes", "table9.3", "--json", str(f))
    assert code == 0 and out == r.report() + f"\nwrote {f}\n"
    assert json.loads(f.read_text()) == r.to_json()
    t = verbs.tf("table6.1:standard", fmin=12.6, fmax=13.0, n=2, png=str(tmp_path / "h.png"))
    assert t.files == [tmp_path / "h.png"] and t.files[0].stat().st_size > 10_000
    assert t.to_json()["png"] == str(tmp_path / "h.png")
    assert abs(t.to_json()["phase_deg"][0]) == pytest.approx(180.0, abs=1e-6)
    assert t.report().endswith(f"  wrote {tmp_path / 'h.png'}")


@pytest.mark.parametrize("argv, hint", [
    (["modes", "eerc-sdfo"], "(did you mean 'eerc-sdof'?)"),
    (["simulate", "--effect", "actuator_frition"], "(did you mean 'actuator_friction'?)"),
    (["simulate", "--effect", "actuator_friction:frction=2"], "(did you mean 'friction'?)"),
    (["simulate", "--specimen", "sdof_fram"], "(did you mean 'sdof_frame'?)"),
    (["simulate", "--specimen", "zzz"], None),  # nothing near: no guess
])
def test_typos_get_a_did_you_mean(capsys, argv, hint):
    code, _, err = run(capsys, *argv)
    assert code == 2 and err.count("\n") == 1, err
    if hint is None:
        assert "did you mean" not in err
    else:
        assert hint in err, err


def test_a_typo_in_a_run_file_key_is_reported_with_its_likely_name(capsys, tmp_path):
    from vtable.runs import read_run

    code, _, err = run(capsys, "simulate", "--duration", "1", "--out", str(tmp_path / "r"))
    assert code == 0, err
    toml = tmp_path / "r.toml"
    toml.write_text('titel = "a typo"\n' + toml.read_text())
    notes = read_run(toml).reports
    assert [n for n in notes if "unknown key 'titel'" in n and "did you mean 'title'?" in n], notes


def test_a_damping_ratio_of_one_is_questioned(capsys, tmp_path):
    """`damping = 1` is legal (critical) but likely 1 %: the run's notes say so (issue 19);
    0.01 passes without a word."""
    from vtable.runs import read_run

    code, _, err = run(capsys, "simulate", "--duration", "1", "--out", str(tmp_path / "r"))
    assert code == 0, err
    toml = tmp_path / "r.toml"
    text = toml.read_text()
    assert "damping = 0.01" in text
    assert not [n for n in read_run(toml).reports if "of critical" in n]
    toml.write_text(text.replace("damping = 0.01", "damping = 1"))
    hints = [n for n in read_run(toml).reports if "of critical" in n]
    assert len(hints) == 1 and "damping = 1 is 100% of critical" in hints[0], hints
    assert "write 0.01" in hints[0]


def test_a_displacement_in_the_wrong_unit_gets_a_hint(capsys, tmp_path):
    """avg_hdisp written in inches but declared mm: the loop fit fails (R² < 0.5) and the
    notes name the unit that brings x_t to x_c's scale (issue 19); declared right, no hint."""
    code, _, err = run(capsys, "simulate", "--duration", "11", "--out", str(tmp_path / "r"))
    assert code == 0, err
    toml = tmp_path / "r.toml"
    code, out, err = run(capsys, "identify", str(toml))
    assert code == 0 and "is it in" not in out, out
    toml.write_text(toml.read_text() + '\n[units]\navg_hdisp = "mm"\n')
    code, out, err = run(capsys, "identify", str(toml), "--json")
    assert code == 0, err
    notes = [n for n in json.loads(out)["runs"][0]["notes"] if "is it in" in n]
    assert len(notes) == 1 and "avg_hdisp is declared mm" in notes[0], notes
    assert 'is it in inches? ([units] avg_hdisp = "in")' in notes[0]


def test_identify_on_a_table_that_cannot_pitch(capsys, tmp_path):
    """LNEC's uniaxial table with a light SDOF frame (issue 19): vtable's own run carries
    no channel that is zero by construction (no lateral accelerometers on a planar
    table), and Table 3.1's coupled row is named for the translation it holds."""
    spec = tmp_path / "light.toml"
    spec.write_text('[specimen]\nkind = "sdof"\nweight_kip = 5.0\nheight_in = 60.0\n'
                    'frequency_hz = 4.0\ndamping = 0.02\n')
    code, _, err = run(capsys, "simulate", "--table", "lnec-st1d", "--specimen", str(spec),
                       "--duration", "20", "--out", str(tmp_path / "l"))
    assert code == 0, err
    code, out, err = run(capsys, "identify", str(tmp_path / "l.toml"), "--json")
    assert code == 0, err
    d = json.loads(out)["runs"][0]
    assert not [n for n in d["reports"] + d["notes"] if "is constant" in n], d["reports"]
    cases = [r["case"] for r in d["table_3_1"]]
    assert cases == ["fixed base", "translational coupling"], cases
    assert "does not pitch" in d["skipped"]["table 3.1: base rotation coupling"]
    assert d["table_3_1"][1]["f_hz"] < d["table_3_1"][0]["f_hz"] < 4.2


def test_a_run_file_given_as_a_model_configuration_says_what_reads_it(capsys, tmp_path):
    """modes and margins take a model configuration; a run file (format vtable-run/1) is
    named as one, with the verbs that read a run (not 'unknown key command')."""
    p = tmp_path / "run.toml"
    p.write_text('format = "vtable-run/1"\n[table]\npreset = "eerc"\n[command]\nkind = "random"\n')
    for cmd in ("margins", "modes"):
        code, out, err = run(capsys, cmd, str(p))
        assert code == 2 and out == "" and err.count("\n") == 1
        assert "a run file (vtable-run/1), not a model configuration" in err
        assert "vtable identify RUN.toml" in err and "unknown key" not in err
