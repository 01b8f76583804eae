"""Issue 18, acceptance 1: on campaigns made with `vtable simulate` as the README shows, one
catalog effect hidden (1 % sensor noise), `diagnose` ends with exactly the hidden effect
and the virtual table's own pitch system and Table B.5 RC filter — nothing else. The
whole set (every effect, noise-free and noisy) is benchmarks/bench_readme_campaigns.py;
here the issue's own example (friction 3 kip) and a 2 ms valve lag: in both, a foundation
used to stand in for the RC filter."""

from __future__ import annotations

import pytest
from readme_campaigns import campaign, expected

from vtable import verbs


@pytest.mark.parametrize("hidden", ["actuator_friction", "valve_dynamics"])
def test_a_readme_campaign_gives_exactly_the_hidden_effect_and_the_tables_own(
        hidden, tmp_path):
    d = verbs.diagnose(campaign(hidden, 0.01, tmp_path))
    assert sorted(d.final_effects) == expected(hidden), d.verdict
    assert d.unexplained is None and d.final_error < 1.5 * d.noise_floor, d.verdict
    p = d.final.effects
    assert p["force_feedback_filter"]["rc"] == pytest.approx(0.01, rel=0.1)  # Table B.5
    if hidden == "actuator_friction":
        assert p[hidden]["friction"] == pytest.approx(3.0, rel=0.05)  # kip, as hidden
    else:
        assert p[hidden]["tau"] == pytest.approx(0.002, rel=0.1)  # s, its default
