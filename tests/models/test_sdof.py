import dataclasses

import numpy as np
import pytest
from reference import TABLE_7_2

from vtable.analytic import TableSDOF
from vtable.analytic.closed_forms import effective_mass, effective_mass_limits
from vtable.analytic.sdof import hurwitz_7_10, tf_7_9
from vtable.params import presets


@pytest.mark.parametrize("row", list(TABLE_7_2))
def test_table_7_2_margins(row):
    gm, pm = TABLE_7_2[row]
    m = TableSDOF(presets.table_sdof(f"table7.2:{row}")).margins()
    assert m.gain_margin == pytest.approx(gm, abs=0.02)
    assert m.phase_margin == pytest.approx(pm, abs=0.5)


def test_table_7_1_standard_equals_table_7_2_standard():
    a = TableSDOF(presets.table_sdof("table7.1:standard")).margins()
    b = TableSDOF(presets.table_sdof("table7.2:standard")).margins()
    assert a.gain_margin == b.gain_margin and a.phase_margin == b.phase_margin


def test_eq_7_9_with_corrected_a2_is_the_state_space_model():
    p = presets.table_sdof("table7.2:standard")
    f = np.linspace(0.2, 30, 400)
    num, den = tf_7_9(p)
    s = 2j * np.pi * f
    np.testing.assert_allclose(np.polyval(num, s) / np.polyval(den, s),
                               TableSDOF(p).freqresp(f, "x_t", "x_c"), rtol=1e-10)
    # the characteristic polynomial of eq 7.7 is eq 7.9's denominator
    np.testing.assert_allclose(TableSDOF(p).characteristic_polynomial(), den / den[0], rtol=1e-9)
    # the printed a2 (ξ_s in place of ξ_o) does not reproduce it
    ol, st = p.open_loop, p.structure
    printed_a2 = (2 * (1 + st.u) * st.omega_s**2 * st.xi_s / ol.omega_o
                  + 2 * st.xi_s * st.omega_s + ol.k_o)
    assert abs(printed_a2 - den[3]) / den[3] > 0.05


def test_hurwitz_7_10_agrees_with_eigenvalues():
    p = presets.table_sdof("table7.2:standard")
    assert all(c > 0 for c in hurwitz_7_10(tf_7_9(p)[1]))
    hot = dataclasses.replace(p, open_loop=dataclasses.replace(p.open_loop, k_o=90.0))
    assert not TableSDOF(hot).is_stable()
    assert min(hurwitz_7_10(tf_7_9(hot)[1])) < 0
    assert not TableSDOF(hot).routh_hurwitz().stable


def test_peak_and_notch_near_structure_frequency():
    # Fig 7.6 (bare-table loop, f_s = 2.90 Hz, ξ_s = 0.4 %): notch at the structure's
    # frequency, peak below it
    p = presets.table_sdof("table7.2:standard")
    p = dataclasses.replace(p, open_loop=presets.open_loop("table6.1:standard"),
                            structure=dataclasses.replace(p.structure, f_s=2.90, xi_s=0.004))
    f = np.linspace(1.5, 4.0, 5001)
    h = np.abs(TableSDOF(p).freqresp(f, "x_t", "x_c"))
    assert f[np.argmin(h)] == pytest.approx(2.90, abs=0.01)
    assert f[np.argmax(h)] < 2.90 and h.max() > 1.8 and h.min() < 0.2


def test_effective_mass_limits_7_17_to_7_20():
    m_t, m_s, f_s, xi = 1.0, 0.6, 2.87, 0.01
    lim = effective_mass_limits(m_t, m_s, xi)
    assert abs(effective_mass(0.01, m_t, m_s, f_s, xi)) == pytest.approx(lim["low"], rel=1e-3)
    assert abs(effective_mass(200.0, m_t, m_s, f_s, xi)) == pytest.approx(lim["high"], rel=1e-3)
    # at resonance the structure adds m_s/(2ξ) in magnitude (the scale of 7.19-7.20) ...
    at = effective_mass(f_s, m_t, m_s, f_s, xi)
    assert abs(at - m_t) == pytest.approx(lim["below"] - m_t, rel=1e-3)
    # ... and the real part swings from above m_t just below f_s to below it just above
    f = np.linspace(2.0, 3.8, 20001)
    me = effective_mass(f, m_t, m_s, f_s, xi)
    assert f[np.argmax(me.real)] < f_s < f[np.argmin(me.real)]
    assert me.real.max() - me.real.min() == pytest.approx(lim["below"] - m_t, rel=0.03)
    assert me.real.min() < lim["high"] < me.real.max()
