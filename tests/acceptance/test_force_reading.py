"""Force channels whose reading the runs do not declare (`vtable.diagnose.reading`).

The independent truth simulator's friction campaigns (tests/truth: its own Coulomb law,
its own oil column) measured as A·ΔP or through load cells, written without
`[table.horizontal] force_measured`: a plain `diagnose` must read them as the truth did —
switching to A·ΔP only where the runs show it, never where they were load cells — and try
nothing where the runs declare the reading or the model holds no force stage.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
import truth
from conftest import run_cli

from vtable.diagnose.calibration import Calibration
from vtable.diagnose.engine import Diagnoser
from vtable.diagnose.reading import force_stage, undeclared
from vtable.models.physics import Physics, nominal_open_loop
from vtable.params import presets
from vtable.runs import read_run
from vtable.tables.eerc import virtual_table

FRICTION_KIP = 3.0  # the truth's, total over the three actuators


def _runs(folder: Path, force_measured: str | None, strip: bool) -> list:
    """The truth's three runs (random 0.1 and 0.3 in, El Centro 2 in) of the SDOF frame
    with friction, its force channels as `force_measured` (None: A·ΔP, undeclared); `strip`
    takes the declaration out of the run files."""
    spec = truth.sdof(68.0, 219.0, 2.87, 0.02)
    decl = truth.perturb(spec, seed=21, frequency=0.03, damping=1.5, weight=0.05)
    table = truth.eerc_table(effects={"actuator_friction": {"friction": FRICTION_KIP}},
                             force_measured=force_measured)
    cmds = [("random_0", truth.random_command(12.0, (0, 25), peak_in=0.1, seed=24)),
            ("random_1", truth.random_command(12.0, (0, 25), peak_in=0.3, seed=25)),
            ("earthquake", truth.earthquake_command("elcentro", peak_in=2.0))]
    out = []
    for k, (name, cmd) in enumerate(cmds):
        path = truth.write_run(folder / name, truth.simulate(table, spec, cmd, fs=200.0), decl,
                               noise=0.01, seed=80 + k)[0]
        if strip:
            text = Path(path).read_text()
            cut = text.replace(f'[table.horizontal]\nforce_measured = "{force_measured}"\n', "")
            assert cut != text
            Path(path).write_text(cut)
        out.append(read_run(path))
    return out


@pytest.fixture(scope="module")
def pressure(tmp_path_factory):
    """The A·ΔP campaign (undeclared) and its diagnosis."""
    folder = tmp_path_factory.mktemp("dp")
    runs = _runs(folder, None, False)
    return runs, Diagnoser(runs).diagnose(), folder


def test_undeclared_pressure_forces_are_found(pressure):
    _, d, _ = pressure
    r = d.force_reading
    assert r is not None and (r["assumed"], r["tried"], r["found"]) == \
        ("load_cell", "delta_p", "delta_p"), r
    assert d.final.force_measured == "delta_p"
    assert "actuator_friction" in d.final_effects, d.headline
    assert d.final.effects["actuator_friction"]["friction"] == pytest.approx(FRICTION_KIP,
                                                                             rel=0.05)
    # read as load cells, the friction leaves the force residual of a missing effect
    assert r["error_after"] < 0.7 * r["error_before"] and r["z"] > 5
    # near the noise (2.1 x here): what is left is the truth's sharper sign(ẋ) (its
    # tanh smoothing at 0.127 mm/s, vtable's at 1 mm/s), not the reading
    assert d.final_error <= 2.5 * d.noise_floor, d.headline
    steps = dict(d.history())
    assert steps["force read as delta_p"] == pytest.approx(r["error_after"])
    errors = [e for _, e in d.history()]
    assert errors == sorted(errors, reverse=True)  # every step lowers the error
    assert "force read as delta_p" in d.headline and len(d.headline) <= 200
    f = [f for f in d.findings if f["kind"] == "force_measured"]
    assert len(f) == 1 and 'force_measured = "delta_p"' in f[0]["action"]
    assert f[0]["numbers"]["error_after"] == pytest.approx(r["error_after"])
    js = d.to_json()
    assert js["force_reading"]["found"] == "delta_p" and js["force_reading"]["declared"] is None


def test_undeclared_load_cells_are_kept(tmp_path_factory):
    d = Diagnoser(_runs(tmp_path_factory.mktemp("lc"), "load_cell", True)).diagnose()
    r = d.force_reading
    assert r is not None and (r["tried"], r["found"]) == ("delta_p", "load_cell"), r
    assert r["error_after"] > r["error_before"] and r["why_not"]
    assert d.final.force_measured is None
    assert "actuator_friction" in d.final_effects, d.headline
    assert d.final.effects["actuator_friction"]["friction"] == pytest.approx(FRICTION_KIP,
                                                                             rel=0.05)
    assert not [f for f in d.findings if f["kind"] == "force_measured"]
    assert any("do not declare what their force channels measure" in n for n in d.notes)


def test_declared_readings_and_models_without_a_force_stage_are_not_tried(tmp_path):
    declared = _runs(tmp_path / "declared", "delta_p", strip=False)
    assert not undeclared(declared)
    stripped = _runs(tmp_path / "stripped", "delta_p", strip=True)
    assert undeclared(stripped)
    # runs without force channels: nothing to read
    bare = [dataclasses.replace(r, channels={c: v for c, v in r.channels.items()
                                              if not c.endswith("_force")})
            for r in stripped]
    assert not undeclared(bare)
    base = Physics(nominal_open_loop(), presets.specimen("sdof_frame"))
    vt = virtual_table()
    assert not force_stage(base, vt)
    assert not force_stage(base.with_effect("valve_dynamics"), vt)
    assert force_stage(base.with_effect("actuator_friction"), vt)


def test_a_drive_from_the_diagnosis_reads_the_forces_as_it_found(pressure, tmp_path):
    """`vtable drive --from` reuses the reading a diagnosis kept, where the runs still do
    not declare it (and not where they do)."""
    from vtable.verbs.compensation import calibrated, diagnosis_reading

    runs, d, _ = pressure
    path = tmp_path / "d.json"
    path.write_text(json.dumps(d.to_json()))
    assert diagnosis_reading(str(path), runs) == "delta_p"
    declared = _runs(tmp_path / "declared", "delta_p", strip=False)
    assert diagnosis_reading(str(path), declared) is None
    model, how = calibrated(runs, [], Calibration(), str(path), [])
    assert model.physics_.force_measured == "delta_p" and "as fitted" in how


def test_compare_says_the_reading_it_assumed(pressure):
    _, _, folder = pressure
    paths = [str(folder / f"{n}.toml") for n in ("random_0", "random_1", "earthquake")]
    code, out, err = run_cli(["compare", *paths, "--with", "actuator_friction"])
    assert code == 0, err
    assert "do not declare what their force channels measure" in out, out
    code, out, err = run_cli(["compare", *paths, "--with", "valve_dynamics"])
    assert code == 0 and "force channels measure" not in out, err  # no force stage
