"""platen_resonator: an undeclared mass-spring-damper on the platen, fitted on runs of the
independent truth simulator (tests/truth), whose resonator is its own code."""

from __future__ import annotations

import functools
import json
import tempfile
from pathlib import Path

import pytest
import truth

from vtable.cli import main

#: the truth's resonator: 9 t at 12 Hz, ξ 3 %, on the EERC table (platen 45.4 t) carrying
#: the SDOF frame; the runs declare the frame, not the resonator
M_R, F_R, XI_R = 9000.0, 12.0, 0.03


@functools.cache
def resonator_campaign() -> list[str]:
    """Random 0-25 Hz at 0.1 and 0.5 in, El Centro at 2 in; 14 s; 200 Hz; 1 % noise."""
    folder = Path(tempfile.mkdtemp(prefix="vtable-resonator-"))
    table = truth.eerc_table(pitch="none", effects={"platen_resonator": {
        "m_r": M_R, "f_r": F_R, "xi_r": XI_R}})
    spec = truth.sdof(68.0, 219.0, 2.87, 0.02)
    paths = truth.campaign(folder, table, spec, spec, fs=200.0, noise=0.01, seed=3,
                           duration_s=14.0, spans_in=(0.1, 0.5), quake_peak_in=2.0)
    return [str(p) for p in paths]


def test_compare_fits_the_truths_resonator(capsys):
    paths = resonator_campaign()
    assert main(["compare", *paths, "--with", "platen_resonator", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    p = d["params"]["platen_resonator"]
    platen = d["base_fit"]["table.platen_mass_kg"]["fitted"]
    assert p["f_r"] == pytest.approx(F_R, rel=0.03)
    assert p["m_r"] / 100 * platen == pytest.approx(M_R, rel=0.20)  # % of the platen
    assert p["xi_r"] == pytest.approx(XI_R, rel=0.5)
    assert d["error"] < 1.5 * d["noise_floor"], (d["error"], d["noise_floor"])
    # without it the same model misses by far more than the noise
    assert main(["compare", *paths, "--json"]) == 0
    bare = json.loads(capsys.readouterr().out)
    assert bare["error"] > 3 * d["error"], (bare["error"], d["error"])


@functools.cache
def undocumented_campaign() -> list[str]:
    """LNEC's table with a 800 kg resonator at 8.3 Hz (ξ 5 %) nobody declared (the runs say
    no specimen): pink noise 0.5-25 Hz, 30 s, at 0.2 and 0.6 in; 200 Hz; 1 % noise."""
    folder = Path(tempfile.mkdtemp(prefix="vtable-undocumented-"))
    table = truth.lnec_table(effects={"platen_resonator": {"m_r": 800.0, "f_r": 8.3,
                                                           "xi_r": 0.05}})
    out = []
    for k, peak in enumerate((0.2, 0.6)):
        cmd = truth.random_command(30.0, (0.5, 25.0), peak_in=peak, seed=40 + k, pink=True)
        res = truth.simulate(table, truth.none(), cmd, fs=200.0)
        out.append(str(truth.write_run(folder / f"pink_{k}", res, truth.none(), noise=0.01,
                                       seed=50 + k)[0]))
    return out


def test_what_identification_finds_is_the_resonators_evidence():
    """On runs that declare no specimen, identify's structure check finds the undeclared
    resonance; `platen_resonator.evidence` holds it (frequency within 5 %, mass within
    30 % of the truth's), and the selection's prior is centred there: the values the runs
    show cost nothing. A campaign that declares its specimen shows none."""
    from vtable.diagnose.campaign import Campaign
    from vtable.diagnose.selection import implausibility
    from vtable.effects.registry import get as effect
    from vtable.effects.table import TableView
    from vtable.runs import read_run

    camp = Campaign.of([read_run(p) for p in undocumented_campaign()])
    e = effect("platen_resonator")
    values, where = e.evidence(camp)
    platen = camp.table.table.geometry.mass
    assert values["f_r"] == pytest.approx(8.3, rel=0.05)
    assert values["m_r"] / 100 * platen == pytest.approx(800.0, rel=0.30)
    assert 0.02 < values["xi_r"] < 0.1
    assert "identified on" in where
    plain = TableView.of(camp.table)
    shown = TableView(**{**plain.__dict__, "evidence": {"platen_resonator": (values, where)}})
    assert all(z == pytest.approx(0.0, abs=1e-12)
               for _, z in implausibility("platen_resonator", values, shown))
    assert max(abs(z) for _, z in implausibility("platen_resonator", values, plain)) > 0.5
    declared = Campaign.of([read_run(p) for p in resonator_campaign()])
    assert e.evidence(declared) is None


def test_a_diagnosis_starts_the_resonator_where_identify_found_it():
    """The undocumented resonator's campaign diagnosed: the notes say what the runs show,
    the resonator is added near the truth's; with no round run, the finding `shown` says
    what the runs show that the model does not hold."""
    from vtable.diagnose.engine import Diagnoser
    from vtable.runs import read_run

    runs = [read_run(p) for p in undocumented_campaign()]
    d = Diagnoser(runs, catalog=["platen_resonator", "sensor_filter"], workers=1).diagnose()
    assert any(n.startswith("platen_resonator: the runs show") for n in d.notes)
    assert d.final_effects == ["platen_resonator"], d.verdict
    assert d.final.effects["platen_resonator"]["f_r"] == pytest.approx(8.3, rel=0.03)
    none = Diagnoser(runs, catalog=["platen_resonator"], workers=1, max_rounds=0).diagnose()
    shown = [f for f in none.findings if f["kind"] == "shown"]
    assert len(shown) == 1 and "platen_resonator" in shown[0]["what"]
    assert shown[0]["numbers"]["f_r"] == pytest.approx(8.3, rel=0.05)


#: a heavy specimen nobody declared, as on LNEC's table: 1500 kg (76 % of the platen) at
#: 2 Hz, ξ 2 %; the table's accelerometer on a mount (17 Hz, ζ 0.09, a 30 Hz low-pass)
#: with a zero of -0.08 m/s²
M_EQ, F_EQ, XI_EQ = 1500.0, 2.0, 0.02


@functools.cache
def earthquake_run(record: str = "elcentro", seed: int = 5, fs: float = 200.0,
                   noise: float = 0.015) -> str:
    """The lab's other kind of run: an earthquake at LNEC's scale (time scale 1.811, 2 in
    peak), ~25 s, on LNEC's table carrying the undeclared resonator: a short, narrow-band
    record whose x_t/x_c (8 averages, 0.4 Hz lines) resolves the resonance's frequency and
    mass but not its damping (El Centro; the synthetic record's, not even those)."""
    folder = Path(tempfile.mkdtemp(prefix="vtable-undocumented-eq-"))
    table = truth.lnec_table(effects={
        "platen_resonator": {"m_r": M_EQ, "f_r": F_EQ, "xi_r": XI_EQ},
        "sensor_mount": {"f_m": 17.0, "zeta_m": 0.09, "f_c": 30.0},
        "sensor_offset": {"zero_m_s2": -0.08}})
    cmd = truth.earthquake_command(record, peak_in=2.0, seed=seed)
    res = truth.simulate(table, truth.none(), cmd, fs=fs)
    return str(truth.write_run(folder / "quake", res, truth.none(), noise=noise, seed=seed)[0])


@pytest.mark.parametrize("record, seed, fs, noise", [
    ("elcentro", 5, 200.0, 0.015), ("elcentro", 5, 256.0, 0.015),
    ("elcentro", 7, 200.0, 0.03), ("synthetic", 6, 200.0, 0.015)])
def test_a_short_record_that_resolves_part_of_the_resonance_seeds_the_resonator(
        record, seed, fs, noise):
    """What identification finds is evidence even where the record resolves only part of
    it: on an earthquake's x_t/x_c the resonator structure wins by far, its damping
    unresolved; the frequency and mass it gives start the diagnosis's resonator, which is
    added, the error ending within the noise. Measured on the first case: before (the whole
    resonance or nothing), the resonator was screened out and only the zero added, 33.7 %
    -> 27.1 % (6.1 x the floor); now 33.7 % -> 6.96 % (floor 4.43 %), the resonator at
    73.5 %, 2.00 Hz, ξ 0.023 (the truth's 76 %, 2 Hz, 0.02). A lightly damped valley lies
    between the grid's frequencies (1.2, 2.3, 4.2 Hz, ...): without the evidence no start
    lands in it. At 256 Hz, at 3 % noise and on a synthetic record (which shows no
    evidence: the grid finds it there) the same resonator is found."""
    from vtable.diagnose.campaign import Campaign
    from vtable.diagnose.engine import Diagnoser
    from vtable.effects.registry import get as effect
    from vtable.runs import read_run

    run = read_run(earthquake_run(record, seed, fs, noise))
    camp = Campaign.of([run])
    platen = camp.table.table.geometry.mass
    shown = effect("platen_resonator").evidence(camp)
    if record == "elcentro":
        values, where = shown
        assert values["f_r"] == pytest.approx(F_EQ, rel=0.05), (values, where)
        assert "xi_r" not in values and "resolve not all of it" in where
    d = Diagnoser([run], catalog=["platen_resonator", "sensor_offset", "sensor_mount",
                                  "valve_dynamics"]).diagnose()
    assert "platen_resonator" in d.final_effects, d.headline
    p = d.final.effects["platen_resonator"]
    assert p["f_r"] == pytest.approx(F_EQ, rel=0.03), p
    assert p["m_r"] / 100 * platen == pytest.approx(M_EQ, rel=0.2), p
    assert d.final_error < 2 * d.noise_floor and d.final_error < d.limits.reference, \
        d.headline


def test_the_evidence_holds_what_the_records_resolve(monkeypatch):
    """`platen_resonator.evidence` over runs that resolve a resonance in part: the median
    of each value over the runs that resolve it, the others left out (they start at their
    defaults), and its note says how much the records resolve."""
    from types import SimpleNamespace

    import vtable.effects.platen_resonator as pr
    from vtable.ident.undeclared import Resonance

    found = {"a": Resonance("a", 3.0, None, None), "b": Resonance("b", 3.2, None, 0.5),
             "c": Resonance("c", 3.1, None, 0.7)}
    monkeypatch.setattr(pr, "undeclared_resonance", lambda run: found[run])
    values, where = pr.EFFECT.evidence(SimpleNamespace(runs=["a", "b", "c"]))
    assert values == {"f_r": 3.1, "m_r": pytest.approx(60.0)}
    assert where.endswith("the records resolve not all of it")
    values, where = pr.EFFECT.evidence(SimpleNamespace(runs=["a"]))
    assert values == {"f_r": 3.0} and where.endswith("the records resolve its frequency alone")
    found["a"] = Resonance("a", 3.0, 0.04, 0.5)
    values, where = pr.EFFECT.evidence(SimpleNamespace(runs=["a"]))
    assert values == {"f_r": 3.0, "m_r": 50.0, "xi_r": 0.04} and "resolve" not in where
