"""identify's "resonator" structure (eq 7.9 with the valve lag, the mass ratio free): a
resonance on the platen that the run does not declare, found and held while the loop is
quoted. Against the independent truth simulator (tests/truth: LNEC's table under P
control with a platen resonator; none on the null), not vtable's models; the structure
itself is eq 7.9 (`vtable.analytic.sdof.tf_7_9`) at τ = 0 to 1e-12."""

from __future__ import annotations

import numpy as np
import pytest

from vtable.analytic.sdof import tf_7_9
from vtable.ident.fits import h_resonator_lag
from vtable.ident.report import identify_run
from vtable.params.loops import OpenLoop, StructureRatios, TableSDOFParams
from vtable.runs import read_run

K_O = 1.9345e-3 * 129.93 / 0.012456  # LNEC's design k_o, 1/s (K_q k_d / A)
M_T = 1975.1


def test_the_structure_is_eq_7_9_without_lag():
    p = TableSDOFParams(OpenLoop(f_o=9.5, xi_o=0.43, k_o=19.9), StructureRatios(3.2, 0.08, 0.5))
    num, den = tf_7_9(p)
    f = np.array([0.3, 1.0, 3.0, 3.2, 5.0, 10.0, 20.0])
    s = 2j * np.pi * f
    h = h_resonator_lag(f, 9.5, 0.43, 19.9, 0.0, 3.2, 0.08, 0.5)
    assert np.abs(np.polyval(num, s) / np.polyval(den, s) / h - 1).max() < 1e-12


def _run(tmp_path, effects, seed):
    import truth
    table = truth.lnec_table(effects=effects)
    cmd = truth.random_command(60.0, (0.0, 40.0), rms_in=0.06, seed=seed, pink=True)
    res = truth.simulate(table, truth.none(), cmd, fs=200.0)
    return read_run(truth.write_run(tmp_path / "run", res, declared=truth.none(), noise=0.01,
                                    seed=seed + 1)[0])


@pytest.mark.parametrize("m_r, f_r, xi_r", [(800.0, 8.3, 0.05), (1000.0, 3.2, 0.08)])
def test_an_undeclared_resonator_is_found_and_the_loop_quoted(tmp_path, m_r, f_r, xi_r):
    run = _run(tmp_path, {"platen_resonator": {"m_r": m_r, "f_r": f_r, "xi_r": xi_r}}, 11)
    d = identify_run(run).to_json()
    assert d["loop_structure"]["best"] == "resonator", d["loop_structure"]["why"]
    p = d["open_loop"]["params"]
    assert p["k_o"] == pytest.approx(K_O, rel=0.03)
    assert p["f_s"] == pytest.approx(f_r, rel=0.03)
    assert p["xi_s"] == pytest.approx(xi_r, rel=0.3)
    assert p["u"] * M_T == pytest.approx(m_r, rel=0.15)
    assert "does not declare" in d["open_loop"]["note_resonator"]


def test_a_bare_table_has_no_resonator(tmp_path):
    d = identify_run(_run(tmp_path, {}, 21)).to_json()
    assert d["loop_structure"]["best"] != "resonator"
    assert "resonator" not in d["loop_structure"]["candidates"]
    assert d["open_loop"]["params"]["k_o"] == pytest.approx(K_O, rel=0.03)
