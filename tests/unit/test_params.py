import dataclasses

import numpy as np
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
from vtable.params.presets import data


def test_table_b5_survives_si_round_trip():
    servo = presets.eerc_table().servo
    assert servo.to_dict() == pytest.approx({k: v for k, v in data("eerc")["servo"].items()
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
        for key, section in data(name).items():
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


SDOF = {"kind": "sdof", "weight_kip": 68.4, "height_in": 219.0, "frequency_hz": 2.87,
        "damping": 0.01}


@pytest.mark.parametrize("key, value, msg", [
    ("damping", 2, r"damping is a fraction of critical damping, at most 1; got 2 \(2 means "
                   r"200 %\)"),
    ("damping", 60.6, r"got 60.6 \(60.6 means 6060 %\)"),
    ("weight_kip", [68.4], r"\[specimen\].weight_kip: expected a number in kip, got \[68.4\]"),
    ("weight_kip", "68.4", "expected a number in kip, got '68.4'"),
    ("weight_kip", True, "expected a number in kip, got True"),
    ("weight_kip", 1e308, "1e\\+308 kip is not a plausible force"),
    pytest.param("weight_kip", 10**400, "is not a plausible force", id="int-beyond-float"),
    ("frequency_hz", float("nan"), "frequency_hz: expected a finite number in Hz, got nan"),
    ("frequency_hz", float("inf"), "expected a finite number in Hz, got inf"),
    ("frequency_hz", 2e4, r"20000 Hz is not a plausible frequency \(the limit is 10000 Hz\)"),
    ("title", ["a"], r"title: expected a string, got \['a'\]"),
])
def test_specimen_values_must_be_finite_physical_numbers(key, value, msg):
    with pytest.raises(VtableError, match=msg) as e:
        specimen_from_dict({**SDOF, key: value}, "run.toml [specimen]")
    assert "\n" not in str(e.value) and str(e.value).startswith("run.toml [specimen]")


def test_shear_building_limits_are_one_line_errors_without_delay():
    import time

    n = 300
    d = {"kind": "shear_building", "weights_kip": [10.0] * n, "heights_in": list(range(1, n + 1)),
         "frequencies_hz": [1.0 + i for i in range(n)], "damping": 0.02}
    t0 = time.perf_counter()
    with pytest.raises(VtableError, match="300 storeys; vtable models at most 50"):
        specimen_from_dict(d, "run.toml [specimen]")
    assert time.perf_counter() - t0 < 0.5
    with pytest.raises(VtableError, match="heights_in: 2 heights for 3 weights"):
        specimen_from_dict({**d, "weights_kip": [10, 10, 10], "heights_in": [50, 100],
                            "frequencies_hz": [1, 2, 3]}, "run.toml [specimen]")
    with pytest.raises(VtableError, match=r"weights_kip\[1\]: expected a number in kip"):
        specimen_from_dict({**d, "weights_kip": [10, "x"], "heights_in": [50, 100],
                            "frequencies_hz": [1, 2]}, "run.toml [specimen]")
    with pytest.raises(VtableError, match="stiffness_kip_per_in: expected a number in kip/in"):
        specimen_from_dict({**SDOF, "stiffness_kip_per_in": "stiff", "damping_lb_s_per_in": 1},
                           "run.toml [specimen]")


def test_specimen_frequencies_of_a_building_by_stiffness():
    from vtable.analytic.structure import specimen_frequencies

    # two equal storeys m, k: ω² = (3 ∓ √5)/2 · k/m
    b = specimen_from_dict({"kind": "shear_building", "weights_kip": [386.08858, 386.08858],
                            "heights_in": [100, 200], "stiffnesses_kip_per_in": [10, 10],
                            "damping": 0.02})
    k_over_m = units.to_si(10, "kip/in") / b.masses[0]
    expect = [np.sqrt((3 - np.sqrt(5)) / 2 * k_over_m) / (2 * np.pi),
              np.sqrt((3 + np.sqrt(5)) / 2 * k_over_m) / (2 * np.pi)]
    assert specimen_frequencies(b) == pytest.approx(expect, rel=1e-9)
    assert specimen_frequencies(specimen_from_dict(SDOF)) == [2.87]


def test_binary_or_non_utf8_toml_is_one_line(tmp_path):
    p = tmp_path / "bin.toml"
    p.write_bytes(b"\xff\xfe\x00\x01binary")
    with pytest.raises(VtableError, match=r"bin.toml: not UTF-8 text"):
        read_toml(p)
    with pytest.raises(VtableError, match=r"folder.toml: cannot read"):
        (tmp_path / "folder.toml").mkdir()
        read_toml(tmp_path / "folder.toml")


# ---- model files (vtable modes|margins|tf FILE.toml) -------------------------------------
OPEN_LOOP = "f_o_hz = 9.6, xi_o = 0.606, k_o_per_s = 29.5"
ROCK = "[rocking]\nk_theta_lb_in_per_rad = 3.1e10\nc_theta_lb_in_s_per_rad = 2.1e8\n"


def _building(n: int, **over) -> str:
    b = {"weights_kip": [20.0] * n, "heights_in": [100.0 * (i + 1) for i in range(n)],
         "frequencies_hz": [2.0 + 3 * i for i in range(n)], "damping": 0.02, **over}
    body = "\n".join(f"{k} = {v!r}".replace("'", '"') for k, v in b.items())
    return (f'model = "mdof_hybrid"\n[building]\n{body}\n[open_loop]\n'
            f'{OPEN_LOOP.replace(", ", chr(10))}\n{ROCK}')


@pytest.mark.parametrize("text, msg", [
    (f'model = "servo"\n[parameters]\n{OPEN_LOOP.replace("9.6", "1e300")}'
     .replace(", ", "\n"), "f_o_hz: 1e\\+300 Hz is not a plausible frequency"),
    (f'model = "servo"\n[parameters]\n{OPEN_LOOP.replace("29.5", "1e300")}'
     .replace(", ", "\n"), "k_o_per_s: 1e\\+300 1/s is not a plausible frequency"),
    (f'model = "servo"\n[parameters]\n{OPEN_LOOP.replace("0.606", "60.6")}'
     .replace(", ", "\n"), r"xi_o: a loop damping ratio is a fraction of critical, at most 3; "
                           r"got 60.6 \(60.6 means 6060 %\)"),
    (f'model = "servo"\n[parameters]\n{OPEN_LOOP.replace("9.6", "nan")}'
     .replace(", ", "\n"), "f_o_hz: expected a finite number in Hz, got nan"),
    (f'model = "servo"\n[parameters]\n{OPEN_LOOP.replace("9.6", "-inf")}'
     .replace(", ", "\n"), "f_o_hz: expected a finite number in Hz, got -inf"),
    ('model = "table_sdof"\npreset = "table7.2:standard"\n[parameters]\n'
     'structure = { xi_s = 2.0 }\n', "xi_s: a structural damping ratio is a fraction of "
                                     "critical, at most 1; got 2"),
    ('model = "table_sdof"\npreset = "table7.2:standard"\n[parameters]\n'
     'structure = { mass_ratio = 1e9 }\n', "mass_ratio: 1e\\+09 is not a plausible ratio"),
    ('model = "servo"\npreset = 5\n', "preset must be a string, got 5"),
    ('model = "servo"\ntitle = [1]\npreset = "table6.1:standard"\n',
     r"title must be a string, got \[1\]"),
    ('model = "hybrid"\nheight_in = 1e300\npreset = "table9.1"\n',
     "height_in: 1e\\+300 in is not a plausible displacement"),
    (_building(300), "300 storeys; vtable models at most 50"),
    (_building(2, weights_kip="heavy"), r"\[building\].weights_kip: expected a non-empty list "
                                        "of numbers in kip, got 'heavy'"),
    (_building(2, damping=[0.02]), r"\[building\].damping: expected a number, got \[0.02\]"),
    (_building(2, heights_in=[100.0]), "heights_in: 1 heights for 2 weights"),
    (_building(2, kind="sdof"), r'\[building\].kind: expected "shear_building", got .sdof.'),
    ('model = "mdof_hybrid"\nbuilding = 3\n', r"\[building\] must be a table, got int"),
])
def test_model_files_are_bounded_one_line_errors(tmp_path, text, msg):
    import time

    from vtable.analytic import configs

    p = tmp_path / "m.toml"
    p.write_text(text)
    t0 = time.perf_counter()
    with pytest.raises(VtableError, match=msg) as e:
        configs.load(str(p))
    assert "\n" not in str(e.value) and "m.toml" in str(e.value)
    assert time.perf_counter() - t0 < 5


def test_model_file_binary_is_one_line(tmp_path):
    from vtable.analytic import configs

    p = tmp_path / "m.toml"
    p.write_bytes(b"\x00\x01\x02\xff\xfe")
    with pytest.raises(VtableError, match=r"m\.toml: not UTF-8 text"):
        configs.load(str(p))


def test_a_specimen_declared_in_si_is_the_same_specimen():
    """The run format lets every [specimen] key name SI instead (../shared/spec): a mass for
    a weight (kg), heights in m or mm, stiffnesses in N/m, a yield drift in mm."""
    m = units.weight_to_mass(68.4, "kip")
    si = specimen_from_dict({"kind": "sdof", "mass_kg": m, "height_m": 219.0 * 0.0254,
                             "frequency_hz": 2.87, "damping": 0.01}, "run.toml [specimen]")
    ref = specimen_from_dict(SDOF)
    assert si.mass == pytest.approx(ref.mass, rel=1e-14) == pytest.approx(31_025.6, rel=1e-5)
    assert si.height == pytest.approx(ref.height, rel=1e-14) and si.frequency == 2.87
    k = [60.0, 50.0]  # kip/in
    imperial = {"kind": "shear_building", "weights_kip": [20.0, 30.0],
                "heights_in": [50.0, 100.0], "damping": 0.02, "stiffnesses_kip_per_in": k,
                "hysteresis": {"yield_drift_in": [0.5, 0.4], "post_yield_ratio": 0.1}}
    metric = {"kind": "shear_building", "weights_kn": [20 * 4.4482216152605, 30 * 4.4482216152605],
              "heights_mm": [1270.0, 2540.0], "damping": 0.02,
              "stiffnesses_n_per_m": [units.to_si(v, "kip/in") for v in k],
              "hysteresis": {"yield_drift_mm": [12.7, 10.16], "post_yield_ratio": 0.1}}
    a, b = specimen_from_dict(imperial), specimen_from_dict(metric)
    np.testing.assert_allclose(b.masses, a.masses, rtol=1e-14)
    np.testing.assert_allclose(b.heights, a.heights, rtol=1e-14)
    np.testing.assert_allclose(b.stiffnesses, a.stiffnesses, rtol=1e-14)
    np.testing.assert_allclose(b.hysteresis.yield_drift, a.hysteresis.yield_drift, rtol=1e-14)


@pytest.mark.parametrize("d, msg", [
    ({**SDOF, "mass_kg": 100.0}, "'weight_kip' and 'mass_kg' give the same quantity; give one"),
    ({**{k: v for k, v in SDOF.items() if k != "height_in"}, "height_m": "2"},
     r"\[specimen\].height_m: expected a number in m, got '2'"),
    ({"kind": "shear_building", "masses_kg": [1000.0, "x"], "heights_m": [1.0, 2.0],
      "damping": 0.02, "frequencies_hz": [2.0, 5.0]},
     r"\[specimen\].masses_kg\[1\]: expected a number in kg, got 'x'"),
    ({**{k: v for k, v in SDOF.items() if k != "weight_kip"}, "mass_kg": -5.0},
     r"\[specimen\].mass_kg: expected a number >= 0 in kg, got -5.0"),
    ({**{k: v for k, v in SDOF.items() if k != "weight_kip"}, "mass_kg": [1.0, 2.0]},
     r"\[specimen\].mass_kg: expected a number in kg, got \[1.0, 2.0\]"),
    ({**{k: v for k, v in SDOF.items() if k != "weight_kip"}, "masses_kg": [1.0, 2.0]},
     "unknown key 'masses_kg'"),  # another kind's key stays as given
])
def test_si_specimen_keys_are_checked_under_their_own_names(d, msg):
    with pytest.raises(VtableError, match=msg) as e:
        specimen_from_dict(d, "run.toml [specimen]")
    assert "\n" not in str(e.value)


def test_physics_effects_checked_once_and_passed_on():
    """A Physics fills its effects' defaults and bounds-checks them; a replace of another
    field passes the checked effects on as they are (a fit sets parameters hundreds of
    times), while a new effects dict is checked again."""
    from vtable.models.physics import Physics, nominal_open_loop

    spec = SDOFSpecimen(weight=units.to_si(68.4, "kip"), frequency=2.8, damping=0.02,
                        height=units.to_si(100.0, "in"))
    ph = Physics(nominal_open_loop(), spec, {"actuator_friction": {}})
    assert ph.effects["actuator_friction"]["friction"] == pytest.approx(1.0)  # its default
    moved = dataclasses.replace(ph, specimen=dataclasses.replace(spec, frequency=3.1))
    assert moved.effects is ph.effects and moved.specimen.frequency == pytest.approx(3.1)
    with pytest.raises(VtableError, match=r"friction = 40 kip is outside \[0.01, 30\]"):
        ph.with_effect("actuator_friction", {"friction": 40.0})
    with pytest.raises(VtableError, match="outside"):
        dataclasses.replace(ph, effects={"actuator_friction": {"friction": 0.0}})
