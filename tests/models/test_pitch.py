import dataclasses

import numpy as np
import pytest
from reference import TABLE_9_2_MODES, TABLE_9_2_REAL_ROOTS

from vtable import units
from vtable.analytic import HybridModel, MDOFHybrid, MechanicalModel, TwoDirectionalTable
from vtable.analytic.closed_forms import combined_rocking, feedback_spring, pitch_loop_from_springs
from vtable.analytic.mechanical import a13_matrices
from vtable.analytic.pitch import two_directional
from vtable.errors import VtableError
from vtable.params import HybridParams, RockingSpring, ShearBuilding, presets


def _with_fs(p: HybridParams, f_s: float, xi_s: float | None = None) -> HybridParams:
    st = dataclasses.replace(p.structure, f_s=f_s,
                             xi_s=p.structure.xi_s if xi_s is None else xi_s)
    return dataclasses.replace(p, structure=st)


def test_table_9_2_modes():
    m = HybridModel(presets.hybrid("table9.1")).modes()
    assert len(m.oscillatory) == 2 and len(m.real_roots) == 3
    for mode, (f, xi) in zip(m.oscillatory, TABLE_9_2_MODES, strict=True):
        assert mode.f_hz == pytest.approx(f, rel=0.003)
        assert mode.damping == pytest.approx(xi, rel=0.003)
    np.testing.assert_allclose(sorted(m.real_roots), sorted(TABLE_9_2_REAL_ROOTS), rtol=0.003)


@pytest.mark.parametrize("f_s, f_ratio, xi_ratio", [(1.0, 0.98, 1.14), (5.0, 0.73, 10.7)])
def test_figs_9_4_and_9_5_trend(f_s, f_ratio, xi_ratio):
    # §9.5 text: f_c/f_s from 0.98 at 1 Hz to 0.72-0.73 at 5 Hz; ξ_c/ξ_s from 1.14 to 10.7
    p = presets.hybrid("table9.1")
    first = HybridModel(_with_fs(p, f_s)).modes().first
    assert first.f_hz / f_s == pytest.approx(f_ratio, rel=0.02)
    assert first.damping / p.structure.xi_s == pytest.approx(xi_ratio, rel=0.02)


def test_section_9_6_coupled_damping():
    p = presets.hybrid("table9.1")
    assert HybridModel(_with_fs(p, 2.87, 0.0)).modes().first.damping == pytest.approx(0.0333,
                                                                                       rel=0.02)
    assert HybridModel(_with_fs(p, 2.87, 0.20)).modes().first.damping == pytest.approx(0.168,
                                                                                        rel=0.02)


def test_section_8_6_4_notch_at_fixed_base_and_pitch_peak_at_coupled():
    model = HybridModel(presets.hybrid("table9.1"))
    f = np.linspace(1.5, 4.0, 25001)
    x_eff = np.abs(model.freqresp(f, "x_eff", "x_c"))
    th = np.abs(model.freqresp(f, "theta_h", "x_c"))
    f_c = model.modes().first.f_hz
    assert f[np.argmin(x_eff)] == pytest.approx(2.87, rel=0.002)  # the fixed-base f_s
    assert f[np.argmax(th)] == pytest.approx(f_c, rel=0.01)
    x_t = np.abs(model.freqresp(f, "x_t", "x_c"))
    assert f[np.argmin(x_t)] < 2.87  # x_t's notch moves below f_s when the table pitches


def test_hybrid_outputs_are_consistent():
    model = HybridModel(presets.hybrid("table9.1"), height=units.to_si(219, "in"))
    f = np.array([0.5, 2.5, 9.0])
    H = model.freqresp(f)
    out = {n: H[:, i, 0] for i, n in enumerate(model.outputs)}
    np.testing.assert_allclose(out["x_eff"], out["x_t"] + out["theta_h"], rtol=1e-12)
    np.testing.assert_allclose(out["theta"] * units.to_si(219, "in"), out["theta_h"], rtol=1e-12)
    np.testing.assert_allclose(out["a_t"], -(2 * np.pi * f) ** 2 * out["x_t"], rtol=1e-9)
    assert abs(abs(out["x_t"][0]) - 1) < 0.01  # tracks the command at low frequency


def test_two_directional_equals_hybrid_with_springs_at_that_frequency():
    # Eqs 8.25-8.30: with θ_c = 0 the pitch loop *is* the spring k_v(ω) + iω c_v(ω); so at
    # every frequency eq 8.16 equals eq 8.37 built with k_θ = k_p + k_v(ω), c_θ = c_p + c_v(ω)
    p2 = two_directional(21.0)
    two = TwoDirectionalTable(p2)
    inertia = presets.eerc_table().geometry.pitch_inertia
    w_p = 2 * np.pi * p2.f_p
    k_p, c_p = inertia * w_p**2, 2 * p2.xi_p * w_p * inertia
    for f in (0.7, 2.58, 6.0, 15.0):
        r = combined_rocking(k_p, c_p, inertia, p2.pitch_loop, f)
        hyb = HybridModel(HybridParams(open_loop=p2.open_loop, structure=p2.structure,
                                       f_theta=r["f_theta"], xi_theta=r["xi_theta"]))
        for out in ("x_t", "theta_h", "x_s"):
            assert two.freqresp(np.array([f]), out, "x_c")[0] == pytest.approx(
                hyb.freqresp(np.array([f]), out, "x_c")[0], rel=1e-9)


def test_two_directional_at_coupled_frequency_reproduces_table_8_1():
    p2 = two_directional(13.0)
    inertia = presets.eerc_table().geometry.pitch_inertia
    w_p = 2 * np.pi * p2.f_p
    r = combined_rocking(inertia * w_p**2, 2 * p2.xi_p * w_p * inertia, inertia,
                         p2.pitch_loop, 2.58)
    assert units.from_si(r["k_theta"], "lb-in/rad") == pytest.approx(2.22e10, rel=1e-9)
    assert units.from_si(r["c_theta"], "lb-in-s/rad") == pytest.approx(3.70e8, rel=1e-9)
    # and the coupled modes agree with the hybrid model (Figs 8.4-8.5: "virtually the same")
    for f_r in (13.0, 21.0):
        first = TwoDirectionalTable(two_directional(f_r)).modes().first
        ref = HybridModel(presets.hybrid("table8.1")).modes().first
        assert first.f_hz == pytest.approx(ref.f_hz, rel=0.002)
        assert first.damping == pytest.approx(ref.damping, rel=0.01)


def test_section_8_6_2_pitch_loop_from_springs():
    inertia = presets.eerc_table().geometry.pitch_inertia
    k_v, c_v = units.to_si(7.72e9, "lb-in/rad"), units.to_si(1.04e8, "lb-in-s/rad")
    assert pitch_loop_from_springs(k_v, c_v, 2.58, 13.0, inertia).xi_o == pytest.approx(0.035,
                                                                                       abs=0.003)
    assert pitch_loop_from_springs(k_v, c_v, 2.58, 21.0, inertia).xi_o == pytest.approx(0.50,
                                                                                       abs=0.02)
    with pytest.raises(VtableError, match=r"must exceed 12\.5"):
        pitch_loop_from_springs(k_v, c_v, 2.58, 12.0, inertia)
    # the inverse is exact
    ol = pitch_loop_from_springs(k_v, c_v, 2.58, 21.0, inertia)
    k, c = feedback_spring(inertia, ol, 2.58)
    assert (k, c) == pytest.approx((k_v, c_v), rel=1e-12)


def test_mdof_with_one_storey_is_the_hybrid_model():
    geo = presets.eerc_table().geometry
    spec = presets.specimen("table8_1")
    hyb = presets.hybrid("table8.1")
    d = presets.data("models")["table8_1"]
    building = ShearBuilding(weights=(spec.weight,), heights=(spec.height,), damping=spec.damping,
                             frequencies=(spec.frequency,))
    mdof = MDOFHybrid(hyb.open_loop, geo.mass, geo.pitch_inertia,
                      RockingSpring.from_dict(d["rocking"]), building)
    np.testing.assert_allclose(np.sort_complex(mdof.poles()),
                               np.sort_complex(HybridModel(hyb).poles()), rtol=1e-9)
    f = np.array([1.0, 2.5, 7.0])
    np.testing.assert_allclose(mdof.freqresp(f, "x_t", "x_c"),
                               HybridModel(hyb).freqresp(f, "x_t", "x_c"), rtol=1e-9)


def test_mdof_building_on_the_table():
    geo = presets.eerc_table().geometry
    hyb = presets.hybrid("table8.1")
    rock = RockingSpring.from_dict(presets.data("models")["table8_1"]["rocking"])
    b = ShearBuilding.from_dict({"weights_kip": [20, 20, 20], "heights_in": [90, 150, 210],
                                 "damping": 0.02, "frequencies_hz": [3.0, 8.5, 12.5]})
    model = MDOFHybrid(hyb.open_loop, geo.mass, geo.pitch_inertia, rock, b)
    assert model.is_stable()
    # eq 4.24: Σ m h² / Σ m h for equal masses
    assert units.from_si(model.effective_height, "in") == pytest.approx(
        (90**2 + 150**2 + 210**2) / (90 + 150 + 210))
    # the first coupled mode is below the first fixed-base mode, as for the SDOF frame
    assert 2.0 < model.modes().first.f_hz < 3.0


def test_mechanical_model():
    p = presets.mechanical("table9.3")
    model = MechanicalModel(p)
    m = model.modes()
    assert m.oscillatory[1].f_hz == pytest.approx(6.71, abs=0.01)  # §9.10
    A, _ = a13_matrices(p)
    np.testing.assert_allclose(np.sort_complex(model.poles()),
                               np.sort_complex(np.linalg.eigvals(A)), rtol=1e-12)
    assert abs(model.freqresp(np.array([0.01]), "x_t", "x_c")[0] - 1) < 1e-3
    # hybrid vs mechanical second coupled mode 8.19 vs 6.71 Hz (§9.10)
    assert HybridModel(presets.hybrid("table9.1")).modes().oscillatory[1].f_hz == pytest.approx(
        8.19, abs=0.01)
