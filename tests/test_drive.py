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
    it is; the lab run measured with it, through --update, brings it within 3 %."""
    _, _, x_eff0, run = drive("friction", "elcentro")
    T = target("elcentro")
    first = nrms(x_eff0, T)
    _, _, x_eff1, _ = drive("friction", "elcentro", update=run)
    updated = nrms(x_eff1, T)
    _, x_as_is, _ = drive_as_is("friction")
    assert first < nrms(x_as_is, T) / 2, (first, nrms(x_as_is, T))
    assert updated <= 0.03 and updated < first, (first, updated)


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
    assert "the table's limit (Table 2.2)" in err and "at t = " in err


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
    doc = (Path(__file__).resolve().parents[1] / "docs" / "drive.md").read_text()
    keys = set(result) | set(result["settings"]) | set(result["baselines"])
    for m in (result["drive"], *result["baselines"].values()):
        keys |= set(m) | set(m.get("spectrum", {}))
    missing = sorted(k for k in keys if f"`{k}`" not in doc)
    assert not missing, missing
