"""Compare, diagnose, add the missing effect, watch the error fall — on virtual-table
campaigns with a hidden effect (1 % noise, 200 Hz, random 0-25 Hz at two spans + El
Centro)."""

from __future__ import annotations

import json

import pytest
from conftest import HIDDEN, effect_campaign, effect_diagnosis

from vtable.errors import VtableError
from vtable.runs import write_run


@pytest.mark.parametrize("hidden", list(HIDDEN))
def test_hidden_effect_ranks_first_and_closes_the_gap(hidden):
    truth, diag, d = effect_diagnosis((hidden,))
    first = d.rounds[0]
    assert first.ranking[0].effect == hidden, [c.effect for c in first.ranking[:3]]
    assert first.added == hidden
    true_err = diag.score(truth).error
    closed = (d.start_error - first.ranking[0].error_after) / (d.start_error - true_err)
    assert closed >= 0.9, closed
    # fitted parameters near the truth
    for k, v in HIDDEN[hidden].items():
        assert first.ranking[0].params[k] == pytest.approx(v, rel=0.1)
    # and then it stops: nothing else is invented
    assert d.final_effects == [hidden]
    assert d.rounds[-1].added is None


def test_null_case_adds_nothing():
    _, _diag, d = effect_diagnosis(())
    assert d.final_effects == [] and d.rounds[0].added is None
    assert d.verdict.startswith("no missing effect")
    assert d.start_error < 2 * d.noise_floor


def test_two_effects_found_in_two_rounds():
    _, _diag, d = effect_diagnosis(("pitch_flexibility", "actuator_friction"))
    added = [r.added for r in d.rounds if r.added]
    assert added == ["pitch_flexibility", "actuator_friction"]
    assert d.final_error < 2 * d.noise_floor
    h = [e for _, e in d.history()]
    assert h == sorted(h, reverse=True)  # the error falls each round


def test_json_has_the_spec_keys():
    _, _, d = effect_diagnosis(("pitch_flexibility",))
    j = json.loads(json.dumps(d.to_json()))
    for k in ("format", "start_effects", "start_error", "noise_floor", "rounds",
              "final_effects", "final_error", "verdict"):
        assert k in j
    assert j["format"] == "vtable-diagnosis/1"
    r0 = j["rounds"][0]
    assert r0["added"] == "pitch_flexibility"
    c = r0["ranking"][0]
    assert {"effect", "error_after", "params", "evidence"} <= set(c)
    assert "pitch" in c["evidence"] and "removes" in c["evidence"]


def test_cli_diagnose_writes_json_rrd_and_report(tmp_path, capsys):
    from vtable.cli import main
    from vtable.viz.rerun_scene import read_rrd

    _, runs = effect_campaign(("pitch_flexibility",))
    paths = []
    for i, r in enumerate(runs):
        write_run(r, tmp_path / f"run{i}")
        paths.append(str(tmp_path / f"run{i}.toml"))
    code = main(["diagnose", *paths, "--json", str(tmp_path / "d.json"), "--rerun",
                 str(tmp_path / "d.rrd"), "--report", str(tmp_path / "d.html")])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "round 1: added pitch_flexibility" in out and "error history:" in out
    assert "[####" in err  # the progress bar
    j = json.loads((tmp_path / "d.json").read_text())
    assert j["final_effects"] == ["pitch_flexibility"]
    assert j["final_error"] < j["start_error"] / 10
    html = (tmp_path / "d.html").read_text()
    assert "<h2>Error waterfall</h2>" in html and "<h2>Round 1: added pitch_flexibility" in html
    assert html.count("data:image/png;base64,") >= 3  # waterfall + transfer functions
    rrd = read_rrd(tmp_path / "d.rrd")
    assert "/diagnosis/error" in rrd
    assert any(k.endswith("/pitch/measured") for k in rrd)
    assert any("model_1_pitch_flexibility" in k for k in rrd)
    errs = [v[0] for v in rrd["/diagnosis/error"][0].column("Scalars:scalars").to_pylist()]
    assert errs == pytest.approx([j["start_error"], j["final_error"]])


def test_cli_compare(tmp_path, capsys):
    from vtable.cli import main

    _, runs = effect_campaign(("pitch_flexibility",))
    paths = []
    for i, r in enumerate(runs):
        write_run(r, tmp_path / f"c{i}")
        paths.append(str(tmp_path / f"c{i}.toml"))
    code = main(["compare", *paths, "--with", "pitch_flexibility", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    d = json.loads(out)
    assert d["error"] < 0.02 and d["params"]["pitch_flexibility"]["k_theta"] == pytest.approx(
        2.22e10, rel=0.05)


def test_robustness_messages(tmp_path):
    from vtable.diagnose.engine import Diagnoser

    _, runs = effect_campaign(())
    r0 = runs[0]
    no_cmd = type(r0)(**{**r0.__dict__, "name": "nocmd",
                         "channels": {k: v for k, v in r0.channels.items() if k != "h_span"}})
    with pytest.raises(VtableError, match=r"nocmd: channel 'h_span' .* is missing"):
        Diagnoser([no_cmd, runs[1]])
    other = type(r0)(**{**r0.__dict__, "name": "other",
                        "meta": {**r0.meta, "specimen": {**r0.meta["specimen"],
                                                          "frequency_hz": 3.1}}})
    with pytest.raises(VtableError, match="other: a different configuration"):
        Diagnoser([runs[0], other])
    short = type(r0)(**{**r0.__dict__, "name": "short", "time": r0.time[:300],
                        "channels": {k: v[:300] for k, v in r0.channels.items()}})
    with pytest.raises(VtableError, match=r"short: 300 samples .* shorter than one 512"):
        Diagnoser([short])
