"""A building's damping per mode (issue 18): `damping` one ratio, a list (one per mode), or
Rayleigh damping `damping_rayleigh = [[f1, ξ1], [f2, ξ2]]`, read from the run format and
carried by every model — the analytic MDOF model (eq 4.5 on the hybrid table), the linear
and reduced models' `mechanics`, and the MuJoCo table's eigen-tendons.

The check is independent of how vtable builds its damping: each model's fixed-base
specimen block (M, K, C) is eigen-analysed as a first-order system, and its modes must carry
exactly the declared ratios; Rayleigh damping must be α M + β K with α, β solved here from
the two anchors.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import scipy.linalg

from vtable.analytic.mdof import MDOFHybrid
from vtable.analytic.structure import building_matrices, modal_damping
from vtable.errors import VtableError
from vtable.mjcf import build
from vtable.models.linear_table import mechanics
from vtable.params import presets
from vtable.params.specimen import specimen_from_dict
from vtable.tables.bodies import specimen_damping
from vtable.tables.eerc import virtual_table

KIP, INCH, G = 4448.2216152605, 0.0254, 9.80665
FREQS = [3.0, 8.0, 12.0]
BUILDING = {"kind": "shear_building", "weights_kip": [20.0, 20.0, 15.0],
            "heights_in": [90.0, 150.0, 210.0], "frequencies_hz": FREQS}
PER_MODE = [0.015, 0.04, 0.07]
RAYLEIGH = [[3.0, 0.02], [12.0, 0.05]]  # anchored at modes 1 and 3


def _modes(M, K, C):
    """Frequencies (Hz) and damping ratios of M q̈ + C q̇ + K q = 0, ascending."""
    n = len(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = scipy.linalg.eigvals(A)
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(np.abs(lam))]
    return np.abs(lam) / (2 * np.pi), -lam.real / np.abs(lam)


def _rayleigh(anchors):
    """α, β of ξ(ω) = α/(2ω) + βω/2 through the anchors (solved here, not by vtable)."""
    (f1, x1), (f2, x2) = anchors
    w1, w2 = 2 * math.pi * f1, 2 * math.pi * f2
    beta = 2 * (x2 * w2 - x1 * w1) / (w2**2 - w1**2)
    alpha = 2 * x1 * w1 - beta * w1**2
    return alpha, beta


@pytest.fixture(scope="module")
def vt():
    return virtual_table()


def test_the_run_format_reads_one_ratio_per_mode_and_rayleigh_anchors():
    b = specimen_from_dict({**BUILDING, "damping": PER_MODE})
    assert b.damping == tuple(PER_MODE) and b.rayleigh is None
    assert specimen_from_dict(b.to_dict()) == b  # round trip through TOML's table
    r = specimen_from_dict({**BUILDING, "damping_rayleigh": RAYLEIGH})
    assert r.damping is None and r.rayleigh == ((3.0, 0.02), (12.0, 0.05))
    assert r.to_dict()["damping_rayleigh"] == RAYLEIGH
    assert specimen_from_dict(r.to_dict()) == r
    assert r.rayleigh_coefficients() == pytest.approx(_rayleigh(RAYLEIGH), rel=1e-12)
    one = specimen_from_dict({**BUILDING, "damping": 0.02})
    assert list(modal_damping(one)) == pytest.approx([0.02] * 3, rel=1e-15)


@pytest.mark.parametrize("over, msg", [
    ({"damping": [0.02, 0.03]}, r"damping: expected a number, got \[0.02, 0.03\]: a list gives "
                                "one ratio per mode, 3 here"),
    ({"damping": [0.02, 0.03, 2.0]}, "damping is a fraction of critical damping, at most 1"),
    ({"damping": [0.02, "x", 0.03]}, r"damping\[1\]: expected a number"),
    ({"damping": 0.02, "damping_rayleigh": RAYLEIGH}, "give exactly one of damping and "
                                                      "damping_rayleigh"),
    ({}, "give exactly one of damping and damping_rayleigh"),
    ({"damping_rayleigh": [[3.0, 0.02]]}, r"expected \[\[f1_hz, xi1\], \[f2_hz, xi2\]\]"),
    ({"damping_rayleigh": [[3.0, 0.02], [3.0, 0.05]]}, "two different frequencies"),
    ({"damping_rayleigh": [[3.0, 0.02], [12.0, 0.2]]}, "need a negative α"),
    ({"damping_rayleigh": [[3.0, 0.05], [12.0, 0.01]]}, "need a negative β"),
    ({"damping_rayleigh": [[3.0, 0.02], [12.0, 1.5]]}, "fraction of critical damping"),
])
def test_bad_damping_is_a_one_line_error(over, msg):
    with pytest.raises(VtableError, match=msg) as e:
        specimen_from_dict({**BUILDING, **over}, "run.toml [specimen]")
    assert "\n" not in str(e.value) and str(e.value).startswith("run.toml [specimen]")


def test_every_model_damps_each_fixed_base_mode_at_its_declared_ratio(vt):
    """The analytic MDOF model's structure block, `mechanics`' slide block (the linear
    virtual table and the reduced model of the diagnosis) and the MuJoCo table's passive
    force on the storey slides: each fixed-base mode at its declared ratio."""
    b = specimen_from_dict({**BUILDING, "damping": PER_MODE})
    # eq 4.5 on the hybrid table: q = [x_t, θ, x_s1..x_s3]; the model's state matrix
    # holds -M⁻¹K and -M⁻¹C, M written here from the equations of `analytic.mdof`
    m, h = np.array(BUILDING["weights_kip"]) * KIP / G, np.array(BUILDING["heights_in"]) * INCH
    m_t, i_t = 4.5e4, 1.4e5
    mdof = MDOFHybrid(presets.hybrid().open_loop, m_t, i_t, presets.hybrid_rocking(), b)
    M = np.zeros((5, 5))
    M[0, 0], M[0, 1], M[1, 1] = m_t + m.sum(), m @ h, i_t + m @ h**2
    M[1, 0] = M[0, 1]
    M[0, 2:] = M[2:, 0] = m
    M[1, 2:] = M[2:, 1] = m * h
    M[2:, 2:] = np.diag(m)
    K = -M @ mdof.A[5:10, :5]
    C = -M @ mdof.A[5:10, 5:10]
    f, zeta = _modes(np.diag(m), K[2:, 2:], C[2:, 2:])
    assert f == pytest.approx(FREQS, rel=1e-9)
    assert zeta == pytest.approx(PER_MODE, rel=1e-9)
    # mechanics: the slab's five coordinates, then the storey drifts
    M, K, C, _, names, _, _ = mechanics(vt, b)
    s = slice(5, None)
    assert names[s] == ["x_s1", "x_s2", "x_s3"]
    f, zeta = _modes(M[s, s], K[s, s], C[s, s])
    assert f == pytest.approx(FREQS, rel=1e-9)
    assert zeta == pytest.approx(PER_MODE, rel=1e-9)
    # MuJoCo: the passive force on the slides for a unit velocity of each
    built = build(vt, b, with_meshes=False)
    m = built.model
    d = mujoco.MjData(m)
    dofs = [m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, j)]
            for j in built.structure_joints]
    C_mj = np.zeros((3, 3))
    for i, dof in enumerate(dofs):
        mujoco.mj_resetData(m, d)
        d.qvel[dof] = 1.0
        mujoco.mj_forward(m, d)
        C_mj[:, i] = -d.qfrc_passive[dofs]
    f, zeta = _modes(M[s, s], K[s, s], C_mj)
    assert f == pytest.approx(FREQS, rel=1e-9)
    assert zeta == pytest.approx(PER_MODE, rel=1e-7)
    assert np.abs(C_mj - specimen_damping(b)).max() < 1e-9 * np.abs(C_mj).max()


def test_rayleigh_damping_is_alpha_m_plus_beta_k_through_its_anchors(vt):
    b = specimen_from_dict({**BUILDING, "damping_rayleigh": RAYLEIGH})
    alpha, beta = _rayleigh(RAYLEIGH)
    Ms, Ks, Cs = building_matrices(b)
    assert np.abs(Cs - (alpha * Ms + beta * Ks)).max() < 1e-12 * np.abs(Cs).max()
    f, zeta = _modes(Ms, Ks, Cs)
    assert f == pytest.approx(FREQS, rel=1e-9)
    w = 2 * np.pi * np.array(FREQS)
    assert zeta == pytest.approx(alpha / (2 * w) + beta * w / 2, rel=1e-9)
    assert zeta[[0, 2]] == pytest.approx([0.02, 0.05], rel=1e-9)  # the anchors
    assert 0.02 < zeta[1] < 0.05 and zeta[1] == pytest.approx(0.0350, abs=1e-4)
    # the same in drift coordinates (u = L d): Lᵀ (α M + β K) L, and in mechanics
    L = np.tril(np.ones((3, 3)))
    C_d = specimen_damping(b)
    assert np.abs(C_d - L.T @ (alpha * Ms + beta * Ks) @ L).max() < 1e-12 * np.abs(C_d).max()
    M, K, C, *_ = mechanics(vt, b)
    s = slice(5, None)
    f, zeta_m = _modes(M[s, s], K[s, s], C[s, s])
    assert zeta_m == pytest.approx(zeta, rel=1e-9)
