"""Issue 20: the drive that makes the specimen feel the target, checked on the independent
truth simulator (tests/truth), never on the model being inverted.

Each configuration's campaign (two random runs and El Centro, 20 s, 2 % sensor noise) is
made by the truth with the specimen's declaration off (`truth.perturb`); `vtable drive`
calibrates its model on the campaign, computes the drive, and the truth plays it: the
effective motion x_t + θh the truth's specimen base feels is compared with the target
(NRMS, and the 5 %-damped pseudo-acceleration spectrum over 0.5-20 Hz). Then the truth's
run of that drive, written as a lab writes it, goes back through `--update`."""

from __future__ import annotations

import functools
import json
import tempfile
from pathlib import Path

import numpy as np
import pytest
import truth

from vtable.cli import main

IN = 0.0254
FS = 200.0
SDOF = truth.sdof(68.0, 219.0, 2.87, 0.01)  # Table 9.2's configuration (Table 8.1's frame)
BUILDING = truth.building([20.0, 20.0, 20.0], [80.0, 150.0, 219.0],
                          frequencies_hz=[2.0, 6.0, 9.5], xi=0.02)
CASES = {
    "sdof": (dict(pitch="hybrid"), SDOF, "pitch_flexibility"),
    "building": (dict(pitch="hybrid"), BUILDING, "pitch_flexibility"),
    # 3 kip of actuator friction in the truth, left out of the model
    "friction": (dict(pitch="hybrid", effects={"actuator_friction": {"friction": 3.0}}),
                 SDOF, "pitch_flexibility"),
}


def effective_height(spec: truth.Specimen) -> float:
    """h of x_eff = x_t + θh (m): the frame's mass height, a building's first-mode
    effective height Σ m h² / Σ m h (eq 4.24), from the truth's own specimen."""
    w, h = np.asarray(spec.weights_kip), np.asarray(spec.heights_in)
    return float(w @ h**2 / (w @ h)) * IN


@functools.cache
def setup(case: str) -> tuple[Path, list[str]]:
    table_kw, spec, _ = CASES[case]
    folder = Path(tempfile.mkdtemp(prefix=f"vtable-drive-{case}-"))
    paths = truth.campaign(folder / "campaign", truth.eerc_table(**table_kw), spec,
                           truth.perturb(spec, seed=5), fs=FS, duration_s=20.0, seed=3,
                           quake_peak_in=2.0)
    return folder, [str(p) for p in paths]


def synthetic_target(folder: Path) -> str:
    """A Kanai-Tajimi record made into a displacement by the truth, as a target CSV."""
    cmd = truth.earthquake_command("synthetic", peak_in=2.0, seed=4, fs=FS)
    p = folder / "synthetic.csv"
    rows = "\n".join(f"{t:.6f},{x / IN:.9g}" for t, x in zip(cmd.t, cmd.x, strict=True))
    p.write_text("time,displacement\n" + rows + "\n")
    return str(p)


def play_on_truth(case: str, drive_stem: Path, folder: Path, name: str):
    """The truth plays the drive written at STEM.csv; its x_eff, and its run (2 % noise)
    written as a lab's."""
    table_kw, spec, _ = CASES[case]
    data = np.loadtxt(f"{drive_stem}.csv", delimiter=",", skiprows=1, usecols=(0, 1))
    t, d = data[:, 0], data[:, 1] * IN  # the run format's h_span is in inches
    res = truth.simulate(truth.eerc_table(**table_kw), spec,
                         truth.Command(t, d, "vtable drive"), fs=FS)
    x_eff = res.internal["x_t"] + effective_height(spec) * res.internal["theta"]
    run = truth.write_run(folder / name, res, truth.perturb(spec, seed=5), noise=0.02,
                          seed=21)[0]
    return t, x_eff, str(run)


@functools.cache
def drive(case: str, target: str, update: str | None = None):
    folder, paths = setup(case)
    tgt = synthetic_target(folder) if target == "synthetic" else target
    stem = folder / f"drive_{target}{'_updated' if update else ''}"
    argv = ["drive", *paths, "--target", tgt, "--with", CASES[case][2], "--out", str(stem),
            "--json", str(stem) + ".json"]
    if target == "elcentro":
        argv += ["--target-peak", "2"]
    if update:
        argv += ["--update", update]
    assert main(argv) == 0
    result = json.loads(Path(f"{stem}.json").read_text())
    t, x_eff, run = play_on_truth(case, stem, folder, f"lab_{target}"
                                  + ("_2" if update else ""))
    return result, t, x_eff, run


def target(name: str) -> np.ndarray:
    """The target motion the drive was asked for (vtable's reading of the input: the
    record processed by §9.2, or the CSV), on the drive's grid."""
    from vtable.drive import read_target

    folder, _ = setup("sdof")
    if name == "elcentro":
        return read_target("elcentro", peak=2.0).x
    return read_target(synthetic_target(folder)).x


def nrms(y: np.ndarray, ref: np.ndarray) -> float:
    n = min(len(y), len(ref))
    return float(np.sqrt(np.mean((y[:n] - ref[:n]) ** 2) / np.mean(ref[:n] ** 2)))


def spectrum_error(y: np.ndarray, ref: np.ndarray) -> float:
    """The worst ratio error of the 5 %-damped pseudo-acceleration spectrum of y against
    ref's over 0.5-20 Hz (eqsig's oscillators, not vtable's)."""
    import eqsig.sdof

    n = min(len(y), len(ref))
    periods = 1 / np.geomspace(0.5, 20.0, 40)

    def psa(x):
        a = np.gradient(np.gradient(x[:n], 1 / FS), 1 / FS)
        return eqsig.sdof.pseudo_response_spectra(a, 1 / FS, periods, 0.05)[2]

    return float(np.max(np.abs(psa(y) / psa(ref) - 1)))


@pytest.mark.parametrize("case, record", [("sdof", "elcentro"), ("sdof", "synthetic"),
                                          ("building", "elcentro"),
                                          ("building", "synthetic")])
def test_the_first_lab_run_reproduces_the_target(case, record):
    """Zero iterations on the specimen: the truth, played with the drive, feels the
    target within 5 % NRMS and its response spectrum within ±10 % over 0.5-20 Hz; the
    target sent as it is misses by far more."""
    result, _, x_eff, _ = drive(case, record)
    T = target(record)
    e, sp = nrms(x_eff, T), spectrum_error(x_eff, T)
    assert e <= 0.05 and sp <= 0.10, (e, sp)
    base = result["baselines"]
    # the model's own prediction of the target sent as it is: the figure to beat
    assert base["target as it is"]["nrms"] > 3 * max(e, 0.01), (base, e)
    assert set(base) == {"target as it is", "horizontal-only correction",
                         "time-scale elongation"}
    assert result["iterations"] >= 1 and result["history_nrms"][-1] < 0.02


def test_one_update_brings_the_sdof_frame_within_3_percent():
    _, _, x_eff0, run = drive("sdof", "elcentro")
    result, _, x_eff1, _ = drive("sdof", "elcentro", update=run)
    T = target("elcentro")
    assert nrms(x_eff1, T) <= 0.03, (nrms(x_eff0, T), nrms(x_eff1, T))
    # the lab run's 2 % sensor noise is not fed back: the spectrum stays within ±10 %
    # (with the raw measured error it was 48 % off)
    assert spectrum_error(x_eff1, T) <= 0.10, spectrum_error(x_eff1, T)
    assert any("lab runs used by this drive: 1" in n for n in result["notes"])


def test_friction_the_model_lacks_degrades_gracefully_and_one_update_recovers():
    """3 kip of actuator friction in the truth, none in the model: the first drive is
    worse than where the model is complete but still far better than the target sent as
    it is; the lab run measured with it, through --update, brings it within 3 % and its
    spectrum within 10 % (the miss read from the accelerometers above 2 Hz: from the
    displacement alone, below 5 Hz, the spectrum stayed 19.6 % off at 6-17 Hz)."""
    _, _, x_eff0, run = drive("friction", "elcentro")
    T = target("elcentro")
    first = nrms(x_eff0, T)
    _, _, x_eff1, _ = drive("friction", "elcentro", update=run)
    updated = nrms(x_eff1, T)
    _, x_as_is, _ = drive_as_is("friction")
    assert first < nrms(x_as_is, T) / 2, (first, nrms(x_as_is, T))
    assert updated <= 0.03 and updated < first, (first, updated)
    assert spectrum_error(x_eff1, T) <= 0.10, spectrum_error(x_eff1, T)


def drive_as_is(case: str):
    """The truth under the target sent as it is (the baseline on the truth itself)."""
    folder, _ = setup(case)
    from vtable.drive import read_target

    tgt = read_target("elcentro", peak=2.0)
    stem = folder / "as_is"
    np.savetxt(f"{stem}.csv", np.column_stack([tgt.t, tgt.x / IN]), delimiter=",",
               header="time,h_span", comments="")
    return play_on_truth(case, stem, folder, "lab_as_is")


def test_a_target_beyond_the_table_is_refused_with_the_limit_and_time(capsys):
    _, paths = setup("sdof")
    code = main(["drive", *paths, "--target", "elcentro", "--target-peak", "9", "--with",
                 "pitch_flexibility", "--out", str(setup("sdof")[0] / "too_big")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert "the table's stroke (Table 2.2)" in err and "at t = " in err


def test_from_a_diagnosis_json_reuses_its_fitted_model_without_a_fit(capsys, tmp_path):
    """--from with a diagnosis that holds its fitted values: the drive is computed on that
    model (no fit: the drive equals compensate's on the same model); a value outside its
    bounds for these runs (a diagnosis of other runs) is said, naming the key, and the
    diagnosis's effects are calibrated again."""
    from vtable.diagnose.model import TableModel
    from vtable.drive import compensate, read_target
    from vtable.ident.drive import align
    from vtable.runs import campaign

    _, paths = setup("sdof")
    fitted = TableModel(["pitch_flexibility"]).fit([align(r) for r in campaign(paths)])
    # the base moved off its fit, so that a re-fit could not land on the same values
    base = {k: dict(v) for k, v in fitted.base_.items()}
    key = "loop.f_o_hz" if "loop.f_o_hz" in base else next(iter(base))
    lo, hi = base[key]["bounds"]
    base[key]["fitted"] = lo + 0.3 * (hi - lo)
    diag = tmp_path / "diag.json"
    diag.write_text(json.dumps({"format": "vtable-diagnosis/1",
                                "final_effects": ["pitch_flexibility"], "base": base,
                                "final_params": fitted.physics_.effects}))
    stem = tmp_path / "from_fit"
    code = main(["drive", *paths, "--target", "elcentro", "--target-peak", "2", "--from",
                 str(diag), "--out", str(stem), "--json", f"{stem}.json"])
    out = capsys.readouterr().out
    assert code == 0 and "final model as fitted" in out, out
    values = {k: v["fitted"] for k, v in base.items()}
    values.update({f"pitch_flexibility.{k}": v
                   for k, v in fitted.physics_.effects["pitch_flexibility"].items()})
    model = TableModel(["pitch_flexibility"]).at([align(r) for r in campaign(paths)], values)
    assert model.base_[key]["fitted"] == pytest.approx(base[key]["fitted"])
    expect = compensate(model, read_target("elcentro", peak=2.0), baselines=False)
    got = json.loads(Path(f"{stem}.json").read_text())
    assert got["history_nrms"] == pytest.approx(expect.history, rel=1e-9)
    base[key]["fitted"] = hi * 2
    diag.write_text(json.dumps({"format": "vtable-diagnosis/1",
                                "final_effects": ["pitch_flexibility"], "base": base,
                                "final_params": fitted.physics_.effects}))
    code = main(["drive", *paths, "--target", "elcentro", "--target-peak", "2", "--from",
                 str(diag), "--out", str(stem)])
    out = capsys.readouterr().out
    assert code == 0 and f"{key} = " in out and "outside its bounds" in out, out
    assert "calibrated again on these runs; 3 run(s), with pitch_flexibility" in out, out


def test_the_cap_holds_the_amplification_near_the_fixed_base_and_a_report(tmp_path):
    """--cap 3: the drive's amplification of the target within ±30 % of the frame's
    fixed-base frequency is held near 3 (it needs ~7.7 there), said in a note; the HTML
    report holds the table of figures with the limits used and the figure."""
    _, paths = setup("sdof")
    stem = tmp_path / "capped"
    assert main(["drive", *paths, "--target", "elcentro", "--target-peak", "2", "--with",
                 "pitch_flexibility", "--cap", "3", "--out", str(stem), "--json",
                 f"{stem}.json", "--report", f"{stem}.html"]) == 0
    r = json.loads(Path(f"{stem}.json").read_text())
    amp = r["drive"]["amplification"]
    assert amp["capped"] and amp["near_fixed_base_uncapped"] > 6, amp
    assert amp["near_fixed_base"] <= 3 * 1.15, amp
    assert 2.0 < amp["near_fixed_base_hz"] < 3.8, amp
    assert any("held to the cap 3" in n for n in r["notes"]), r["notes"]
    use = r["drive"]["limit_use"]
    assert 0.3 < use["displacement"] < 0.5 and 0 < use["velocity"] < 1 and 0 < use["force"] < 1
    html = Path(f"{stem}.html").read_text()
    assert html.count("<tr>") == 5 and "data:image/png;base64," in html and "stroke used" in html


def test_model_miss_reads_the_acceleration_above_the_crossover():
    """A 10 Hz miss the displacement sensors do not see (e_x = 0) but the accelerometers
    do (e_a = -ω²x) comes back as that displacement, within 2 % in the record's middle;
    a 0.5 Hz one seen by the displacement comes back from it."""
    from vtable.drive.compensate import model_miss

    t = np.arange(4000) / FS
    for f, e_x, share in ((10.0, 0.0, 1.0), (0.5, 1.0, 0.0)):
        x = 1e-3 * np.sin(2 * np.pi * f * t)
        got = model_miss(e_x * x, FS, share * -(2 * np.pi * f) ** 2 * x)
        mid = slice(1000, 3000)
        assert np.max(np.abs(got[mid] - x[mid])) < 0.02e-3, (f, np.max(np.abs(got[mid] - x[mid])))


def test_from_a_diagnosis_json_with_a_txt_drive_and_a_figure(capsys):
    """--from takes a diagnosis's final effects; --format txt adds the two-column file a
    controller imports; --png draws target, prediction and spectra; a file that is not a
    diagnosis is one line."""
    folder, paths = setup("sdof")
    diag = folder / "diag.json"
    diag.write_text(json.dumps({"format": "vtable-diagnosis/1",
                                "final_effects": ["pitch_flexibility"]}))
    stem = folder / "from_diag"
    code = main(["drive", *paths, "--target", "elcentro", "--target-peak", "2", "--from",
                 str(diag), "--out", str(stem), "--format", "txt", "--png",
                 str(stem) + ".png"])
    out = capsys.readouterr().out
    assert code == 0 and "with pitch_flexibility" in out, out
    rows = np.loadtxt(f"{stem}.txt")
    csv = np.loadtxt(f"{stem}.csv", delimiter=",", skiprows=1, usecols=(0, 1))
    assert rows.shape == csv.shape and np.allclose(rows, csv, rtol=1e-6, atol=1e-9)
    assert rows[0, 1] == 0.0 and abs(rows[-1, 1] - rows[-2, 1]) < 1e-5  # starts, ends still
    assert Path(f"{stem}.png").stat().st_size > 20_000
    (folder / "not.json").write_text("{}")
    code = main(["drive", *paths, "--target", "elcentro", "--from", str(folder / "not.json"),
                 "--out", str(stem)])
    err = capsys.readouterr().err
    assert code == 2 and "not a diagnosis JSON" in err and err.count("\n") == 1


def test_docs_name_every_key_the_drive_json_has():
    result, *_ = drive("sdof", "elcentro")
    doc = (Path(__file__).resolve().parents[2] / "docs" / "drive.md").read_text()
    keys = set(result) | set(result["settings"]) | set(result["baselines"])
    for m in (result["drive"], *result["baselines"].values()):
        keys |= set(m) | set(m.get("spectrum", {}))
    missing = sorted(k for k in keys if f"`{k}`" not in doc)
    assert not missing, missing


def test_a_table_that_declares_no_band_gets_a_drive_and_no_figure_above_a_band():
    """One table: on a table without `band_hz` the drive is computed as on any other, its
    share above a band and the model's |H| there are null (JSON), no above-band note is
    made, and the report says the band is not declared."""
    import dataclasses

    from vtable.diagnose.model import TableModel
    from vtable.drive import compensate, read_target
    from vtable.ident.drive import align
    from vtable.runs import campaign
    from vtable.viz.drive_report import _band

    _, paths = setup("sdof")
    model = TableModel(["pitch_flexibility"]).fit([align(r) for r in campaign(paths)])
    with_band = compensate(model, read_target("elcentro", peak=2.0), baselines=False)
    vt = model.vt
    model.vt = dataclasses.replace(vt, table=dataclasses.replace(
        vt.table, specs=dataclasses.replace(vt.table.specs, bandwidth=None)))
    r = compensate(model, read_target("elcentro", peak=2.0), baselines=False)
    got = r.to_json()
    assert got["settings"]["table_band_hz"] is None
    assert got["table_response"]["table_band"] is None
    assert got["table_response"]["correction_band"] == pytest.approx(
        with_band.response["correction_band"], rel=1e-9)
    assert got["drive"]["above_band_share"] is None
    assert r.history == pytest.approx(with_band.history, rel=1e-9)  # the same drive
    assert not any("band" in n for n in r.notes)
    assert _band(None) == "not declared" and _band(20.0) == "20 Hz"
