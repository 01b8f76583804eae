"""The reduced model's resolution from the effects present (issue 18, deliverable 4) and the
plausibility of an effect's fitted parameters (deliverable 5): the shipped figures against a
fresh measurement, and the selection rule's arithmetic on numbers worked out here."""

from __future__ import annotations

import math
import tomllib

import pytest

from vtable.diagnose import resolution as res
from vtable.diagnose.selection import SELECTION, failing, implausibility, prior_cost
from vtable.diagnose.statistics import Gain
from vtable.effects.registry import BUILT_IN
from vtable.models.physics import Physics, nominal_open_loop
from vtable.params import presets


def _model(effects: dict[str, dict[str, float]]) -> Physics:
    return Physics(nominal_open_loop(), presets.specimen("sdof_frame"), effects)


def test_every_catalog_effect_has_a_figure_saying_how_and_when():
    data = tomllib.loads(res.DATA.read_text(encoding="utf-8"))
    assert data["how"] == res.HOW and data["when"] and data["commit"]
    assert set(data["agreement"]) == {res.BASE, *BUILT_IN}
    for v in data["agreement"].values():
        # the reduced model reproduces the multibody table to well under 1 % (the
        # agreement tests of tests/models/test_effects.py hold each channel to 2 %)
        assert 0.001 < v["nrms"] < 0.01 and v["nrms"] <= v["worst_nrms"] < 0.02
    # the rule's sum against the standard table's pair measured together
    assert data["check"]["summed"] == pytest.approx(data["check"]["measured"], rel=0.05)


@pytest.mark.parametrize("name", [res.BASE, "force_feedback_filter"])
def test_the_shipped_figures_are_what_a_fresh_measurement_gives(name):
    r, group, worst = res.agreement({} if name == res.BASE else {name: {}})
    assert r == pytest.approx(res.shipped()[name], rel=0.02)
    data = tomllib.loads(res.DATA.read_text(encoding="utf-8"))["agreement"][name]
    assert group == data["worst_group"] and worst == pytest.approx(data["worst_nrms"], rel=0.02)


def test_a_models_resolution_adds_each_effects_excess_on_the_squared_scale():
    f = res.shipped()
    b, p, o = f[res.BASE], f["pitch_flexibility"], f["oil_column_air"]
    assert res.resolution() == b
    assert res.resolution(["pitch_flexibility"]) == pytest.approx(p, rel=1e-12)
    # an effect the reduced model follows better than the base adds nothing
    assert o < b and res.resolution(["oil_column_air"]) == b
    two = ["pitch_flexibility", "platen_resonator"]
    r2 = b**2 + (p**2 - b**2) + (f["platen_resonator"] ** 2 - b**2)
    assert res.resolution(two) == pytest.approx(math.sqrt(r2), rel=1e-12)


def test_a_gain_below_the_resolution_of_the_model_with_it_is_not_an_effect():
    """Noise-free (f² = 0): only the resolution stands between a patch and selection."""
    g = Gain(e2_current=6e-5, e2_candidate=2.5e-5, f2=0.0, se=1e-9)  # gain 3.5e-5
    r_pitch = res.shipped()["pitch_flexibility"]
    assert r_pitch**2 > 3.5e-5 > res.shipped()[res.BASE] ** 2
    fails = failing(g, _model({"pitch_flexibility": {}}), "pitch_flexibility")
    assert len(fails) == 1 and "resolution of the reduced model" in fails[0]
    assert f"{r_pitch:.2%}" in fails[0]
    # the same gain for an effect the reduced model follows as well as the base passes
    assert failing(g, _model({"sensor_filter": {}}), "sensor_filter") == []
    # no model: the base's resolution
    assert failing(g) == []
    assert "resolution" in SELECTION and "defaults" in SELECTION


def test_a_fitted_value_far_from_its_default_must_buy_that_distance():
    """force_feedback_filter at rc = 0.3 s, 30 x Table B.5's 0.01 s: z = ln 30 / ln 3."""
    far = _model({"force_feedback_filter": {"rc": 0.3}})
    (what, z), = implausibility("force_feedback_filter", far.effects["force_feedback_filter"])
    assert z == pytest.approx(math.log(30) / math.log(3), rel=1e-9)
    assert "30 x its default 0.01" in what and "Table B.5" in what
    # 1 % noise; the current model's systematic residual 1.1e-3, the candidate removes 55 %
    g = Gain(e2_current=1.2e-3, e2_candidate=5.95e-4, f2=1e-4, se=1e-6)
    cost = prior_cost(g, far, "force_feedback_filter")
    assert cost == pytest.approx(z * z * 0.05 * 1.1e-3, rel=1e-9)  # 48 % of the residual
    assert failing(g) == []  # without the prior the gain would count
    fails = failing(g, far, "force_feedback_filter")
    assert fails and "distance from their defaults" in fails[-1] and "rc 0.3 s" in fails[-1]
    assert "needs 20%" in fails[0]  # 55 % - 48 % charged: 7 % of the residual is left
    # a factor 3 (one σ) costs 5 % of the residual only: the same gain buys it
    near = _model({"force_feedback_filter": {"rc": 0.03}})
    assert prior_cost(g, near, "force_feedback_filter") == pytest.approx(5.5e-5, rel=1e-9)
    assert failing(g, near, "force_feedback_filter") == []
    # at its default nothing is charged
    assert prior_cost(g, _model({"force_feedback_filter": {}}), "force_feedback_filter") == 0
