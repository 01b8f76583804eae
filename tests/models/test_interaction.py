import dataclasses
import json

import numpy as np
import pytest

from vtable import units
from vtable.analytic import HybridModel, MechanicalModel
from vtable.cli import main
from vtable.errors import VtableError
from vtable.params import ShearBuilding, presets
from vtable.signals.processing import process_record
from vtable.signals.records import el_centro
from vtable.signals.spectra import response_spectrum
from vtable.studies import interaction as ia


@pytest.fixture(scope="module")
def frame():
    return presets.specimen("table8_1")  # Table 8.1: 68 kip at 219 in, 2.87 Hz, 1 %


@pytest.fixture(scope="module")
def command():
    return process_record(el_centro())  # §9.2: length scale 3.2801, 4 in peak


def test_hybrid_of_the_frame_is_table_9_2(frame):
    f, xi = ia.coupled_mode(ia.five_models(frame)["hybrid"])
    assert f == pytest.approx(2.54, abs=0.01)  # Table 9.2 first coupled mode
    assert xi == pytest.approx(0.040, abs=0.001)


def test_rocking_and_one_directional_are_limits_of_the_full_models(frame):
    # independent checks: eq A.13 with a rigid horizontal spring is the rocking model;
    # eq 8.37 with a rigid rocking spring is the one-directional model (eq 7.7)
    ms = ia.five_models(frame)
    rigid_h = MechanicalModel(dataclasses.replace(ms["mechanical"].params, f_h=300.0))
    np.testing.assert_allclose(ia.coupled_mode(rigid_h), ia.coupled_mode(ms["rocking"]),
                               rtol=1e-4)
    rigid_r = HybridModel(dataclasses.replace(ms["hybrid"].params, f_theta=3000.0))
    np.testing.assert_allclose(ia.coupled_mode(rigid_r),
                               ia.coupled_mode(ms["one-directional"]), rtol=1e-4)
    # the report's ordering (§9.5): rocking > one-directional > hybrid in coupled frequency
    f = {n: ia.coupled_mode(ms[n])[0] for n in ia.MODELS[1:]}
    assert f["rocking"] > f["one-directional"] > f["hybrid"]


def test_fixed_base_through_the_model_route_is_the_response_spectrum(frame, command):
    T = np.array([0.1, 0.35, 1.0, 2.5])
    psv = ia.psv_spectra(frame, command.acceleration, command.dt, T,
                         names=["fixed base"])["fixed base"]
    ref = response_spectrum(command.acceleration, command.dt, T, frame.damping).psv
    np.testing.assert_allclose(psv, ref, rtol=1e-9)


def test_interaction_vanishes_at_long_periods(frame, command):
    # §9.9: above about 1 s the five spectra coincide
    psv = ia.psv_spectra(frame, command.acceleration, command.dt, [2.5])
    vals = np.array([v[0] for v in psv.values()])
    assert np.ptp(vals) / vals.mean() < 0.03


@pytest.mark.parametrize("f_s, f_ratio, xi_ratio", [(1.0, 0.98, 1.14), (5.0, 0.72, 10.7)])
def test_frequency_sweep_figs_9_4_and_9_5(f_s, f_ratio, xi_ratio):
    spec = presets.specimen("table8_1")
    out = ia.sweep(spec, "frequency", [f_s], names=["hybrid"])["hybrid"][0]
    assert out[0] / f_s == pytest.approx(f_ratio, rel=0.02)
    assert out[1] / spec.damping == pytest.approx(xi_ratio, rel=0.02)


def test_damping_sweep_section_9_6(frame):
    out = ia.sweep(frame, "damping", [0.0, 0.20], names=["hybrid"])["hybrid"]
    assert out[0, 1] == pytest.approx(0.0333, rel=0.02)
    assert out[1, 1] == pytest.approx(0.168, rel=0.02)


def test_mass_and_height_sweeps_widen_the_gap_sections_9_7_9_8(frame):
    for par in ("weight", "height"):
        v = getattr(frame, par)
        f = ia.sweep(frame, par, [0.5 * v, v, 1.5 * v], names=["hybrid"])["hybrid"][:, 0]
        assert f[0] > f[1] > f[2]  # heavier or taller: coupled frequency further below f_s
    with pytest.raises(VtableError, match="sweep parameter"):
        ia.sweep(frame, "colour", [1.0])


def test_building_through_its_first_mode_effective_height():
    b = ShearBuilding.from_dict({"weights_kip": [50.0, 50.0, 50.0], "damping": 0.02,
                                 "heights_in": [100.0, 200.0, 300.0],
                                 "frequencies_hz": [2.0, 5.5, 8.0]})
    s = ia.equivalent_sdof(b)
    h = np.array([100.0, 200.0, 300.0])
    assert units.from_si(s.height, "in") == pytest.approx((h**2).sum() / h.sum())  # eq 4.24
    assert units.from_si(s.weight, "kip") == pytest.approx(50 * ((h / 300) ** 2).sum())
    assert s.frequency == pytest.approx(2.0, rel=1e-3)
    assert s.damping == 0.02


def test_assessment_verdict(frame, command):
    a = ia.assess(frame, command.acceleration, command.dt, "El Centro")
    assert a.modes["hybrid"][0] == pytest.approx(2.54, abs=0.01)
    assert a.elongation == pytest.approx(2.87 / a.modes["hybrid"][0], rel=1e-12)
    assert 0.2 < a.rocking_share < 0.6  # both mechanisms matter (§9.11)
    assert a.psv_at_specimen["hybrid"] < a.psv_at_specimen["fixed base"]
    text = a.verdict()
    assert "coupled period 0.39 s vs fixed-base 0.35 s" in text
    assert "damping 1 % -> 4 %" in text


def test_vtable_assess_cli(tmp_path, capsys):
    assert main(["assess", "table8_1", "--out", str(tmp_path), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["modes"]["hybrid"]["f_hz"] == pytest.approx(2.54, abs=0.01)
    assert "verdict: coupled period 0.39 s" in d["verdict"]
    assert len(d["files"]) == 5
    for f in d["files"]:
        assert (tmp_path / f.split("/")[-1]).stat().st_size > 10_000
    assert main(["assess", "concrete_blocks", "--out", str(tmp_path)]) == 2
    assert "sdof or shear_building" in capsys.readouterr().err


def test_vtable_assess_a_building_file_through_its_first_mode(tmp_path, capsys):
    f = tmp_path / "building.toml"
    f.write_text('[specimen]\nkind = "shear_building"\ntitle = "3-storey frame"\n'
                 "weights_kip = [20.0, 20.0, 20.0]\nheights_in = [80.0, 160.0, 240.0]\n"
                 "frequencies_hz = [3.0, 8.5, 13.0]\ndamping = 0.02\n")
    assert main(["assess", str(f), "--out", str(tmp_path / "plots"), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["modes"]["fixed base"]["f_hz"] == pytest.approx(3.0, rel=1e-3)
    h = np.array([80.0, 160.0, 240.0])
    assert f"at {(h**2).sum() / h.sum():.0f} in" in d["verdict"]  # h_e1, eq 4.24
    assert d["modes"]["hybrid"]["f_hz"] < 3.0


def test_section_9_5_horizontal_only_damping_crosses_the_hybrid_near_6_hz(frame):
    # §9.5: the one-directional model's coupled damping is slightly lower than the
    # hybrid's below about 6 Hz and higher above; §9.10: the mechanical model's is lower
    out = ia.sweep(frame, "frequency", [3.0, 8.0], names=["one-directional", "hybrid",
                                                          "mechanical"])
    assert out["one-directional"][0, 1] < out["hybrid"][0, 1]
    assert out["one-directional"][1, 1] > out["hybrid"][1, 1]
    assert out["mechanical"][0, 1] < out["hybrid"][0, 1]
    assert out["mechanical"][0, 0] == pytest.approx(out["hybrid"][0, 0], rel=0.03)
