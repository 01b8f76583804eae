import numpy as np
import pytest

from vtable.analytic import closed_forms as cf
from vtable.analytic.structure import (
    building_matrices,
    fixed_base_modes,
    stiffness_matrix,
    storey_stiffnesses,
)
from vtable.effects.oil_column_air import chamber_modulus
from vtable.params import OpenLoop, ShearBuilding


def test_effective_heights_of_a_uniform_building():
    n, h = 10, 3.0
    m, hj = np.full(n, 2.0), h * np.arange(1, n + 1)
    # §4.2.2: h_e1 about 2/3 and h_e about 1/2 of the total height
    assert cf.effective_height_first_mode(m, hj) / (n * h) == pytest.approx((2 * n + 1) / (3 * n))
    assert cf.effective_height_least_squares(np.diag(m), hj) / (n * h) == pytest.approx(
        (n + 1) / (2 * n))
    # eq 4.22 with φ₁ = r_θ is eq 4.24
    assert cf.effective_height_mode(np.diag(m), hj, hj) == pytest.approx(
        cf.effective_height_first_mode(m, hj))
    assert cf.modal_mass(m, hj) == pytest.approx(np.sum(m * (hj / hj[-1]) ** 2))


def test_springs_from_frequencies_round_trip():
    m_s, h, f_f = 177.0 * 175.127, 5.56, 2.87
    k_r, k_h = 2.5e9, 7.0e7
    f_r = cf.rocking_coupled_frequency(f_f, m_s, h, k_r)
    f_hr = cf.coupled_frequency(f_f, m_s, h, k_h, k_r)
    assert f_hr < f_r < f_f
    assert cf.rocking_stiffness_from_frequencies(f_f, f_r, m_s, h) == pytest.approx(k_r, rel=1e-12)
    assert cf.horizontal_stiffness_from_frequencies(f_f, f_hr, m_s, h, k_r) == pytest.approx(
        k_h, rel=1e-10)


def test_eq_5_14_and_8_4():
    # four equal actuators on a square of side d: each at distance d/2 from the pitch axis
    assert cf.rocking_stiffness_from_actuators([1.0] * 4, [0.5] * 4, [0, 0], [0, 0]) == 1.0
    # eq 8.4 for a cross-connected pair each side: k_p = (F/Δx) d²
    assert cf.stabilizer_rocking_stiffness(1 / 3.0e8, 5.18) == pytest.approx(3.0e8 * 5.18**2)


def test_eq_8_3_oil_term_and_eq_8_5():
    # no air: β_e = β; oil term alone gives Δx/F = V/(2βA²)
    # eq 8.5 is the oil_column_air effect's law, written once (its file)
    assert chamber_modulus(1.5e9, 0.0, 1e7) == 1.5e9
    beta_e = chamber_modulus(1.5e9, 0.01, 1e7)
    assert 1 / beta_e == pytest.approx(1 / 1.5e9 + 0.01 / 1.4e7)
    c = cf.stabilizer_compliance(area=0.0168, cylinder_length=0.1, line_length=3.0,
                                 line_area=2e-4, beta_e=beta_e)
    assert c == pytest.approx((0.0168 * 0.1 + 2e-4 * 3.0) / (2 * beta_e * 0.0168**2))


def test_feedback_spring_limits_5_15():
    ol = OpenLoop(f_o=12.6, xi_o=0.477, k_o=25.07)
    k, c = cf.feedback_spring(2.0, ol, np.array([0.0, 1e6]))
    # ω -> 0: k = m ω_o k_o/(2ξ_o); ω -> ∞: k -> m ω_o²
    assert k[0] == pytest.approx(2.0 * ol.omega_o * ol.k_o / (2 * ol.xi_o))
    assert k[1] == pytest.approx(2.0 * ol.omega_o**2, rel=1e-6)
    assert c[0] == pytest.approx(2.0 * (2 * ol.xi_o * ol.omega_o - ol.k_o) / (4 * ol.xi_o**2))


def test_shear_building_from_frequencies_is_exact():
    masses = np.array([10.0, 10.0, 5.0])
    k_true = np.array([4000.0, 3000.0, 2000.0])
    w_true, _ = fixed_base_modes(np.diag(masses), stiffness_matrix(k_true))
    f_true = w_true / (2 * np.pi)
    k = storey_stiffnesses(masses, f_true)
    w, _ = fixed_base_modes(np.diag(masses), stiffness_matrix(k))
    np.testing.assert_allclose(w / (2 * np.pi), f_true, rtol=1e-9)
    b = ShearBuilding(weights=tuple(masses * 9.80665), heights=(1.0, 2.0, 3.0), damping=0.05,
                      frequencies=tuple(f_true))
    M, K, C = building_matrices(b)
    # modal damping: every mode at 5 %
    w, phi = fixed_base_modes(M, K)
    np.testing.assert_allclose(np.diag(phi.T @ C @ phi) / (2 * w), 0.05, rtol=1e-9)


def test_impossible_frequencies_are_an_error():
    from vtable.errors import VtableError

    with pytest.raises(VtableError, match="no shear building with these masses"):
        storey_stiffnesses(np.array([10.0, 10.0, 5.0]), [1.5, 1.6, 1.7])
