import numpy as np
import pytest

from vtable.analytic.stability import characteristic_polynomial, routh_hurwitz


@pytest.mark.parametrize("roots, rhp", [
    ([-1, -2, -3], 0),
    ([1, -2], 1),
    ([-0.5 + 3j, -0.5 - 3j, -10], 0),
    ([0.2 + 3j, 0.2 - 3j, -10, -1], 2),
    ([-199.6, -99.3, -46.3, -0.64 + 15.9j, -0.64 - 15.9j, -13.3 + 49.7j, -13.3 - 49.7j], 0),
])
def test_routh_counts_right_half_plane_roots(roots, rhp):
    r = routh_hurwitz(np.real(np.poly(roots)))
    assert r.sign_changes == rhp
    assert r.stable == (rhp == 0)


def test_textbook_example():
    # s³ + s² + 2s + 8: Routh column 1, 1, -6, 8 -> two roots in the right half plane
    r = routh_hurwitz([1, 1, 2, 8])
    np.testing.assert_allclose(r.first_column, [1, 1, -6, 8])
    assert r.sign_changes == 2 and not r.stable


def test_characteristic_polynomial_without_eigenvalues():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(7, 7)) * np.logspace(0, 2, 7)
    np.testing.assert_allclose(characteristic_polynomial(A), np.real(np.poly(A)), rtol=1e-7,
                               atol=1e-7 * np.abs(np.poly(A)).max())
