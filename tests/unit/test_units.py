import numpy as np
import pytest

from vtable import units
from vtable.errors import VtableError


def test_g_in_inches_matches_run_format():
    # run format: 1 g = 386.09 in/s²
    assert units.from_si(units.G, "in/s2") == pytest.approx(386.09, abs=0.005)


def test_report_units_to_si():
    assert units.to_si(1.0, "kip") == pytest.approx(4448.2216152605)
    assert units.to_si(1.0, "psi") == pytest.approx(6894.757293168)
    assert units.to_si(1251.0, "kip-in-s2") == pytest.approx(1251 * 4448.2216152605 * 0.0254)
    assert units.to_si(1.0, "in3/s/psi") == pytest.approx(0.0254**3 / 6894.757293168)
    assert units.to_si(170.0, "gpm") == pytest.approx(170 * 231 * 0.0254**3 / 60)


def test_table_b5_mass_is_a_third_of_100_kips():
    # Table B.5: m_t = 86.3 lb-s²/in = 100 kips/(3g)
    m = units.weight_to_mass(100.0, "kip") / 3
    assert units.from_si(m, "lb-s2/in") == pytest.approx(86.3, abs=0.05)


@pytest.mark.parametrize("unit", sorted(units.UNITS))
def test_round_trip(unit):
    x = np.array([0.0, 1.5, -2.25e7])
    np.testing.assert_allclose(units.from_si(units.to_si(x, unit), unit), x, rtol=1e-15)


def test_unknown_unit_is_a_clear_error():
    with pytest.raises(VtableError, match="unknown unit 'furlong'"):
        units.to_si(1.0, "furlong")


def test_every_unit_has_a_dimension_and_a_plausible_bound():
    assert set(units.DIMENSIONS) == set(units.UNITS)
    assert set(units.DIMENSIONS.values()) <= set(units.PLAUSIBLE_MAX)
    assert units.dimension("kip") == "force" and units.dimension("g") == "acceleration"
    assert units.dimension("in/s2") == units.dimension("cm/s2") == "acceleration"
    assert units.dimension("Hz") == "frequency" and units.dimension("%") == "dimensionless"
    assert units.to_si(250.0, "ms") == pytest.approx(0.25)
    assert units.to_si(980.665, "cm/s2") == pytest.approx(units.G)
    assert units.units_of("time") == ["s", "ms"]
    # a bound in SI: 1e4 Hz, 1e9 kg (the model-file limits of issue 9)
    assert units.PLAUSIBLE_MAX["frequency"] == 1e4 and units.PLAUSIBLE_MAX["mass"] == 1e9


@pytest.mark.parametrize("unit, dim, msg", [
    ("g", "length", "avg_hdisp is a displacement; 'g' is an acceleration unit"),
    ("kip", "length", "avg_hdisp is a displacement; 'kip' is a force unit"),
    ("Hz", "length", "avg_hdisp is a displacement; 'Hz' is a frequency unit"),
    ("psi", "length", "avg_hdisp is a displacement; 'psi' is a pressure unit"),
    ("%", "length", "avg_hdisp is a displacement; '%' is a dimensionless unit"),
    ("rad", "force", "avg_hdisp is a force; 'rad' is an angle unit"),
    ("s", "force", "avg_hdisp is a force; 's' is a time unit"),
])
def test_dimension_mismatch_is_named(unit, dim, msg):
    with pytest.raises(VtableError, match=msg):
        units.check_dimension(unit, dim, "avg_hdisp")
    units.check_dimension("mm", "length", "avg_hdisp")  # the same dimension passes
    with pytest.raises(VtableError, match="unknown unit 'furlong'"):
        units.check_dimension("furlong", "length", "avg_hdisp")


@pytest.mark.parametrize("spelled, unit", [
    ("m/s^2", "m/s2"), ("m/s\u00b2", "m/s2"), ("in/s^2", "in/s2"), ("rad/s^2", "rad/s2"),
    ("kg\u00b7m\u00b2", "kg-m2"), ("kip*in*s^2", "kip-in-s2"), ("in\u00b3/s/psi", "in3/s/psi"),
    ("m^3/s", "m3/s"), ("N\u00b7m", "N-m"),
])
def test_the_other_spellings_labs_write_are_read(spelled, unit):
    assert units.canonical(spelled) == unit and units.known(spelled)
    assert units.factor(spelled) == units.factor(unit)
    assert units.dimension(spelled) == units.dimension(unit)


def test_a_spelling_of_no_unit_stays_an_error():
    assert units.canonical("m/s^4") == "m/s^4" and not units.known("m/s^4")
    assert not units.known(None) and not units.known(2)
    with pytest.raises(VtableError, match=r"unknown unit 'm/s\^4'"):
        units.to_si(1.0, "m/s^4")
