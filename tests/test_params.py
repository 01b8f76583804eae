import dataclasses

import pytest

from vtable import units
from vtable.errors import VtableError
from vtable.params import (
    HybridParams,
    OpenLoop,
    SDOFSpecimen,
    ServoConstants,
    ShearBuilding,
    presets,
    read_toml,
    specimen_from_dict,
)
from vtable.params.presets import _file


def test_table_b5_survives_si_round_trip():
    servo = presets.eerc_table().servo
    assert servo.to_dict() == pytest.approx({k: v for k, v in _file("eerc")["servo"].items()
                                             if k != "source"} | {"source": servo.source})
    assert units.from_si(servo.beta, "psi") == pytest.approx(94000.0)
    assert units.from_si(servo.k_ct, "in3/s/psi") == pytest.approx(0.0787)
    assert servo.k_f == pytest.approx(servo.k_p / servo.area)


def test_geometry_and_specs():
    t = presets.eerc_table()
    assert units.from_si(t.geometry.weight, "kip") == pytest.approx(100.0)
    assert units.from_si(t.geometry.pitch_inertia, "kip-in-s2") == pytest.approx(1251.0)
    assert units.from_si(t.geometry.actuator_line_depth, "in") == pytest.approx(219 - 189.3)
    assert units.from_si(t.specs.weight_capacity, "kip") == pytest.approx(130.0)
    assert units.from_si(t.specs.overhead_clearance, "ft") == pytest.approx(40.0)
    assert [a.name for a in t.actuators] == ["H1", "H2", "H3", "V1", "V2", "V3", "V4",
                                             "P1", "P2", "P3", "P4"]
    h1, p1 = t.actuator("H1"), t.actuator("P1")
    assert units.from_si(h1.area, "in2") == pytest.approx(25.4)
    assert units.from_si(h1.flow, "gpm") == pytest.approx(170)
    assert p1.flow is None and p1.servovalve is None
    assert units.from_si(p1.area, "in2") == pytest.approx(26.0)


def test_every_preset_section_names_its_source():
    for name in ("eerc", "specimens", "models"):
        for key, section in _file(name).items():
            if isinstance(section, dict) and "kind" not in section and key not in (
                    "knob_factors", "control") and not any(isinstance(v, dict) and "source" in v
                                                           for v in section.values()):
                assert "source" in section, f"{name}.toml [{key}] has no source"
    for row in presets.rows("table7.2"):
        assert presets.table_sdof(f"table7.2:{row}").source == "Table 7.2"


def test_knob_factors_scale_table_b5():
    t = presets.eerc_table()
    s = t.horizontal_servo(dataclasses.replace(t.standard.horizontal, gain=10.0))
    assert units.from_si(s.k_t, "in2/s") == pytest.approx(663 * 7.07 / 5.68)
    s5 = t.horizontal_servo(dataclasses.replace(t.standard.horizontal, delta_p=5.0))
    assert units.from_si(s5.k_p, "in/psi") == pytest.approx(0.000274)  # Table B.1 (§B.5)
    s0 = t.horizontal_servo(dataclasses.replace(t.standard.horizontal, delta_p=0.0))
    assert s0.k_p == 0.0
    assert t.knob_factors.factor("pitch", "rate", 10) == 1.015
    with pytest.raises(VtableError, match="tabulated positions: 8, 9, 10"):
        t.horizontal_servo(dataclasses.replace(t.standard.horizontal, gain=9.5))
    with pytest.raises(VtableError, match="no knob factor table for twist"):
        t.knob_factors.factor("twist", "gain", 5)


def test_specimens():
    blocks = presets.specimen("concrete_blocks")
    assert units.from_si(blocks.weight, "kip") == pytest.approx(70.5)
    assert units.from_si(blocks.height, "in") == pytest.approx(10.75 + 29.7)
    frame = presets.specimen("sdof_frame")
    assert isinstance(frame, SDOFSpecimen) and frame.frequency == 2.87
    t51 = presets.specimen("table5_1")
    # Table 5.1: k_s = 57.9 kip/in, c_s = 64.2 lb-s/in, m_s = 68.4 kips
    assert units.from_si(t51.stiffness, "kip/in") == pytest.approx(57.9)
    assert units.from_si(t51.damping_coefficient, "lb-s/in") == pytest.approx(64.2)
    assert t51.frequency == pytest.approx(2.877, abs=1e-3)
    assert t51.damping == pytest.approx(0.0100, abs=1e-4)


def test_table_8_1_is_equivalent_to_table_9_1():
    p81, p91 = presets.hybrid("table8.1"), presets.hybrid("table9.1")
    assert p81.structure.u == pytest.approx(p91.structure.u, rel=1e-12)  # 68/100
    assert p81.structure.v == pytest.approx(p91.structure.v, rel=0.01)  # 6.75 vs 6.8 printed
    assert p81.f_theta == pytest.approx(p91.f_theta, rel=1e-3)  # eq 8.35
    assert p81.xi_theta == pytest.approx(p91.xi_theta, rel=0.005)  # eq 8.36
    m51, m93 = presets.mechanical("table5.1"), presets.mechanical("table9.3")
    assert m51.f_h == pytest.approx(m93.f_h, rel=0.002)
    assert m51.xi_h == pytest.approx(m93.xi_h, rel=0.002)


def test_toml_round_trip_of_nested_params():
    p = presets.hybrid("table9.1")
    assert HybridParams.from_dict(p.to_dict()) == p


@pytest.mark.parametrize("d, msg", [
    ({"kind": "sdof", "weight_kip": -5, "height_in": 219, "frequency_hz": 2.87,
      "damping": 0.01}, "weight_kip must be > 0, got -5"),
    ({"kind": "sdof", "weight_kip": 68, "height_in": 219, "frequency_hz": 2.87},
     "missing key 'damping'"),
    ({"kind": "sdof", "weight_kip": 68, "height_in": 219, "frequency_hz": 2.87, "damping": 0.01,
      "colour": "red"}, "unknown key 'colour'"),
    ({"kind": "sdof", "weight_kip": "heavy", "height_in": 219, "frequency_hz": 2.87,
      "damping": 0.01}, "expected a number in kip"),
    ({"kind": "tower"}, "kind: expected one of none, rigid, sdof, shear_building"),
    ({"kind": "shear_building", "weights_kip": [10, 10], "heights_in": [100, 50],
      "damping": 0.02, "stiffnesses_kip_per_in": [50, 50]}, "heights must increase"),
    ({"kind": "shear_building", "weights_kip": [10, 10], "heights_in": [50, 100],
      "damping": 0.02}, "give exactly one of"),
])
def test_bad_specimens_are_one_line_errors(d, msg):
    with pytest.raises(VtableError, match=msg) as e:
        specimen_from_dict(d, "run.toml [specimen]")
    assert "\n" not in str(e.value) and str(e.value).startswith("run.toml [specimen]")


def test_malformed_and_missing_toml(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("model = [unclosed\n")
    with pytest.raises(VtableError, match=r"bad.toml: malformed TOML"):
        read_toml(bad)
    with pytest.raises(VtableError, match="no such file"):
        read_toml(tmp_path / "missing.toml")


def test_open_loop_validation():
    with pytest.raises(VtableError, match="f_o_hz must be > 0"):
        OpenLoop.from_dict({"f_o_hz": 0.0, "xi_o": 0.5, "k_o_per_s": 25})
    assert ServoConstants.sources()["k_v"].startswith("eq B.6")


def test_shear_building_from_stiffnesses():
    b = ShearBuilding.from_dict({"weights_kip": [20, 20, 10], "heights_in": [80, 160, 240],
                                 "damping": 0.02, "stiffnesses_kip_per_in": [60, 50, 40]})
    assert b.n == 3 and units.from_si(b.mass * units.G, "kip") == pytest.approx(50.0)
