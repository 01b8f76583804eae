import dataclasses

import numpy as np
import pytest
from reference import TABLE_6_1

from vtable.analytic import RCFilterServo, ServoLoop, open_loop_from_servo, servo_from_open_loop
from vtable.analytic.closed_forms import gain_margin_bare, h_at_open_loop_frequency
from vtable.analytic.servo import routh_conditions
from vtable.errors import UnstableError, VtableError
from vtable.params import OpenLoop, presets


@pytest.mark.parametrize("row", list(TABLE_6_1))
def test_table_6_1_margins(row):
    gm, pm = TABLE_6_1[row]
    m = ServoLoop(presets.open_loop(f"table6.1:{row}")).margins()
    assert m.gain_margin == pytest.approx(gm, abs=0.02)
    assert m.phase_margin == pytest.approx(pm, abs=0.3)


def test_gain_margin_closed_form_and_eq_6_19():
    ol = presets.open_loop("table6.1:standard")
    model = ServoLoop(ol)
    assert model.margins().gain_margin == pytest.approx(gain_margin_bare(ol), rel=1e-9)
    # eq 6.19: H(iω_o) is real and negative; the phase crossover is f_o itself
    h = model.freqresp(np.array([ol.f_o]), "x_t", "x_c")[0]
    assert h == pytest.approx(h_at_open_loop_frequency(ol), rel=1e-12)
    assert h.real < 0 and abs(h.imag) < 1e-12
    assert model.margins().f_phase_crossover == pytest.approx(ol.f_o, rel=1e-9)


def test_eq_6_16_round_trip_is_exact():
    c = presets.eerc_table().servo
    ol = open_loop_from_servo(c)
    back = servo_from_open_loop(ol, c)
    for name in ("k_t", "beta", "k_ct"):
        assert getattr(back, name) == pytest.approx(getattr(c, name), rel=1e-12, abs=0)
    # and with velocity feedback present
    cv = dataclasses.replace(c, k_v=0.01)
    back_v = servo_from_open_loop(open_loop_from_servo(cv), cv)
    for name in ("k_t", "beta", "k_ct"):
        assert getattr(back_v, name) == pytest.approx(getattr(cv, name), rel=1e-12, abs=0)


def test_table_b5_open_loop_frequency_is_15_hz():
    # §B.4: f_o = 15.00 Hz fitted on the actuator velocity gives β = 94000 psi
    ol = open_loop_from_servo(presets.eerc_table().servo, feedback=False)
    assert ol.f_o == pytest.approx(15.0, abs=0.05)
    assert ol.k_o == pytest.approx(663 / 25.4)  # eq 6.14c


def test_rc_filter_without_filter_is_the_third_order_loop():
    # B.7 with RC -> infinity (filter passes ΔP unchanged) must equal eq 6.10 through eq 6.16
    c = dataclasses.replace(presets.eerc_table().servo, rc=1e9)
    f = np.linspace(0.1, 40, 300)
    np.testing.assert_allclose(RCFilterServo(c).freqresp(f, "x_t", "x_c"),
                               ServoLoop.from_servo(c).freqresp(f, "x_t", "x_c"), rtol=1e-6)


def test_rc_filter_bare_table_is_stable_with_margin():
    m = RCFilterServo(presets.eerc_table().servo)
    assert m.is_stable() and m.routh_hurwitz().stable
    assert 2.5 < m.margins().gain_margin < 4.5


def test_routh_6_11_agrees_with_eigenvalues():
    c = presets.eerc_table().servo
    assert all(x > 0 for x in routh_conditions(c))
    assert ServoLoop.from_servo(c).is_stable()
    # too much gain and no ΔP feedback: 2ξ_oω_o < k_o (eq 6.17b)
    hot = dataclasses.replace(c, k_t=c.k_t * 20, k_p=0.0)
    assert routh_conditions(hot)[2] < 0
    model = ServoLoop.from_servo(hot)
    assert not model.is_stable()
    assert not model.routh_hurwitz().stable and model.routh_hurwitz().sign_changes == 2
    with pytest.raises(UnstableError, match=r"unstable: eigenvalues with positive real part"):
        model.margins()


def test_time_response_steady_state_sine():
    model = ServoLoop(presets.open_loop("table6.1:standard"))
    t = np.arange(0, 6, 0.001)
    f = 3.0
    y = model.response(t, np.sin(2 * np.pi * f * t))["x_t"]
    H = model.freqresp(np.array([f]), "x_t", "x_c")[0]
    expected = np.abs(H) * np.sin(2 * np.pi * f * t + np.angle(H))
    np.testing.assert_allclose(y[t > 3], expected[t > 3], atol=2e-4)


def test_unknown_output_is_named():
    with pytest.raises(VtableError, match="has no output 'x_q'; expected one of x_t"):
        ServoLoop(OpenLoop(f_o=10, xi_o=0.5, k_o=20)).freqresp([1.0], "x_q", "x_c")
