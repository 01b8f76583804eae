"""specimen_degradation (issue 32, deliverable 2): the specimen's stiffness falls during a
run with the energy it dissipates (k/(1 + δεⁿ), Baber & Noori). Its law against a hand
integration; both models agree (tests/models/test_effects.py's DOSES); the notch it moves is read
from the run alone and gates the effect; and a fit on a campaign the independent truth makes
(tests/truth: its own law, the whole stiffness matrix times 1 − L(1 − e^(−E/E₀)), no vtable
code) predicts the held-out end of the run far better than the time-invariant model."""

import functools
import math
from types import SimpleNamespace

import numpy as np
import pytest
import truth

from vtable.analytic.structure import building_stiffnesses, specimen_frequencies
from vtable.diagnose.campaign import Campaign
from vtable.diagnose.model import TableModel
from vtable.diagnose.stationarity import moved_notch
from vtable.effects.registry import get as effect
from vtable.effects.specimen_degradation import REFERENCE_DRIFT, degrading_storey, storeys
from vtable.errors import VtableError
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.params import presets
from vtable.params.specimen import specimen_from_dict
from vtable.runs import read_run
from vtable.signals import make_command
from vtable.sim import simulate
from vtable.units import INCH

#: a 3-storey shear building: 3 x 25 kip at 110/160/210 in, storeys 120/100/80 kip/in
BUILDING = {"kind": "shear_building", "weights_kip": [25.0, 25.0, 25.0],
            "heights_in": [110.0, 160.0, 210.0], "stiffnesses_kip_per_in": [120.0, 100.0, 80.0],
            "damping": 0.02}
DOSE = {"stiffness_loss": 0.35, "energy_kip_in": 80.0}


def test_the_law_integrated_by_hand():
    """ε̇ = c v²/E_ref, force +k w/(1 + w) d with w = δ εⁿ: a storey at constant drift
    velocity for 1 s has ε = c v²/E_ref and resists with k/(1 + δεⁿ)."""
    k, c, e_ref, delta, n = 2.0e6, 3.0e4, 500.0, 0.2, 0.7
    p = SimpleNamespace(k=k, r=c / e_ref, delta=delta, n=n)
    dz = np.zeros(1)
    z = np.zeros(1)
    v, dt = 0.05, 1e-3
    for _ in range(1000):  # Euler is exact: ε̇ is constant
        degrading_storey(0.0, v, z, p, dz)
        z += dt * dz
    eps = c * v * v / e_ref
    assert z[0] == pytest.approx(eps, rel=1e-9)
    d = 0.01
    f = degrading_storey(d, v, z, p, dz)
    assert -k * d + f == pytest.approx(-k / (1 + delta * eps**n) * d, rel=1e-12)
    # a virgin storey adds nothing
    assert degrading_storey(d, v, np.zeros(1), p, dz) == 0.0


def test_each_storey_s_reference_energy_and_damping():
    """The frame's storey: c_s = 2ξωm and E_ref = ½ k (h/100)²; a building's storeys take
    the first mode's stiffness-proportional damping 2ξ₁k_i/ω₁ and their floor-to-floor
    heights; a bare table has none and the effect cannot be built there."""
    frame = presets.specimen("sdof_frame")
    ((k, m, c, h),) = storeys(frame)
    w = 2 * math.pi * frame.frequency
    assert c == pytest.approx(2 * frame.damping * w * m, rel=1e-12)
    assert k == pytest.approx(m * w * w, rel=1e-12)
    assert h == pytest.approx(frame.height, rel=1e-12)
    b = specimen_from_dict(BUILDING, "building")
    w1 = 2 * math.pi * specimen_frequencies(b)[0]
    rows = storeys(b)
    assert [h for *_, h in rows] == pytest.approx([110 * INCH, 50 * INCH, 50 * INCH])
    for (k_i, m_i, c_i, _), k_b, m_b in zip(rows, building_stiffnesses(b), b.masses,
                                            strict=True):
        assert (k_i, m_i) == pytest.approx((k_b, m_b), rel=1e-12)
        assert c_i == pytest.approx(2 * 0.02 * k_b / w1, rel=1e-12)
    assert REFERENCE_DRIFT == 0.01
    with pytest.raises(VtableError, match="has no storeys to degrade"):
        ReducedModel(Physics(nominal_open_loop(), presets.specimen("none"),
                             {"specimen_degradation": {}}))


def test_a_structure_an_effect_stood_on_the_platen_degrades_in_both_models():
    """Where the run declares no storeys, the structure platen_resonator stands on the
    platen in an undeclared specimen's place degrades (its unit of energy at 10 mm): the
    virtual table and the reduced model agree as they do on a declared specimen, and the
    loss shows in the displacement."""
    cmd = make_command("random", duration=20.0, band=(0.0, 25.0), peak_in=0.15, seed=2)
    res = {"platen_resonator": {"m_r": 50.0, "f_r": 3.2, "xi_r": 0.04}}
    ph0 = Physics(nominal_open_loop(), presets.specimen("none"), res)
    ph1 = Physics(ph0.open_loop, ph0.specimen,
                  {**res, "specimen_degradation": {"delta": 0.05, "exponent": 1.0}})
    r0, r1 = simulate(ph0, cmd, name="intact"), simulate(ph1, cmd, name="degrading")
    out = ReducedModel(ph1).simulate(r1.time, r1.channel("h_span"))
    for c, agree in (("avg_hdisp", 0.005), ("avg_hacc", 0.012)):
        y = r1.channel(c)
        assert np.linalg.norm(out[c] - y) / np.linalg.norm(y) < agree  # 0.24 %, 0.65 %
    x0, x1 = r0.channel("avg_hdisp"), r1.channel("avg_hdisp")
    assert np.linalg.norm(x1 - x0) / np.linalg.norm(x0) > 0.03  # 5.3 %


@functools.cache
def _runs(tmp: str, loss: float = DOSE["stiffness_loss"]) -> list:
    """Two random runs (30 s at 0.5 in, 80 s at 0.4 in) of the frame, degrading by the
    truth's law, declared 2 % off."""
    spec = truth.sdof(68.0, 219.0, 2.87, 0.02)
    decl = truth.perturb(spec, seed=3, frequency=0.02, damping=1.3, weight=0.04)
    table = truth.eerc_table(effects={"specimen_degradation": {**DOSE,
                                                               "stiffness_loss": loss}}
                             if loss else None)
    out = []
    for k, (dur, peak) in enumerate(((30.0, 0.5), (80.0, 0.4))):
        cmd = truth.random_command(dur, (0.0, 25.0), peak_in=peak, seed=20 + k)
        res = truth.simulate(table, spec, cmd, fs=200.0)
        path = truth.write_run(f"{tmp}/deg{round(100 * loss)}_{k}", res, decl, noise=0.01,
                               seed=5 + k)[0]
        out.append(read_run(path))
    return out


def test_the_notch_moves_and_gates_the_effect(tmp_path_factory):
    """x_t/x_c's notch in the truth's degrading 80 s run moves down between its first and
    last third; in the same run without degradation it does not, and the effect says the
    runs show no change to fit."""
    tmp = str(tmp_path_factory.getbasetemp())
    degrading, steady = _runs(tmp)[1], _runs(tmp, 0.0)[1]
    moved = moved_notch(degrading.channel("h_span"), degrading.channel("avg_hdisp"),
                        degrading.fs)
    assert moved is not None and moved[1] < moved[0] < 2.95
    assert moved_notch(steady.channel("h_span"), steady.channel("avg_hdisp"), steady.fs) is None
    e = effect("specimen_degradation")
    assert e.unsupported(Campaign.of(_runs(tmp))) is None
    assert "no change of the specimen" in e.unsupported(Campaign.of(_runs(tmp, 0.0)))


def test_fitted_on_the_first_60_percent_it_predicts_the_end(tmp_path_factory):
    """The truth's degrading campaign, fitted on the runs' first 60 %: the model with the
    degradation predicts the held-out last 40 % at less than half the time-invariant
    model's error."""
    camp = Campaign.of(_runs(str(tmp_path_factory.getbasetemp())))
    plain = TableModel().fit(camp)
    deg = TableModel(start=Physics(nominal_open_loop(camp.table), camp.specimen,
                                   {"specimen_degradation": {}})).fit(camp)
    e0, e1 = plain.score(camp), deg.score(camp)
    assert e1 < 0.5 * e0, (e0, e1)
    assert 1e-3 < deg.physics_.effects["specimen_degradation"]["delta"] < 1.0


def test_a_short_run_alone_is_found_by_its_residual_not_its_notch(tmp_path_factory):
    """The truth's 30 s degrading run diagnosed alone: too short to read a notch
    (`Campaign.notches` empty: it was left unexplained, 27.5 %), but the time-invariant
    model's residual, as a transfer function from the command, changes between the run's
    halves (z far above the screen's); specimen_degradation is added and the error falls
    within 2 x the floor. The same run without degradation: z within the noise."""
    from vtable.diagnose.engine import Diagnoser
    from vtable.diagnose.screen import Z_SCREEN, residual_change

    tmp = str(tmp_path_factory.getbasetemp())
    dg = Diagnoser([_runs(tmp)[0]])
    d = dg.diagnose()
    assert not dg.campaign.notches
    assert dg.campaign.residual_change.change > 5 * Z_SCREEN
    assert d.final_effects == ["specimen_degradation"]
    assert d.final_error < 2.0 * dg.floor < 0.25 * d.start_error
    steady = Diagnoser([_runs(tmp, 0.0)[0]])
    plain = steady.diagnose()
    assert steady.campaign.residual_change is None  # within the noise: nothing to explain
    assert "no change of the specimen" in effect("specimen_degradation").unsupported(
        steady.campaign)
    assert plain.final_effects == []
    ev = residual_change(steady.campaign, plain.stages[-1].predictions)
    assert ev.runs == 1 and ev.change < 0.5 * Z_SCREEN and not ev.present


def test_only_a_steady_command_s_halves_are_compared():
    """A run's halves are compared where its command is at one amplitude with one spectrum:
    a random command is; one whose second half is a third as strong (an earthquake's coda)
    is not, nor a sweep (its band powers differ), so neither reads as a change."""
    from vtable.diagnose.screen import _steady

    fs, n = 200.0, 6000
    rng = np.random.default_rng(3)
    white = np.convolve(rng.standard_normal(n), np.ones(4) / 4, mode="same")
    t = np.arange(n) / fs
    sweep = np.sin(2 * np.pi * (0.5 * t + 0.5 * (20.0 / t[-1]) * t ** 2))
    coda = white * np.where(t < t[-1] / 2, 1.0, 1.0 / 3.0)
    assert _steady(white, n // 2, fs)
    assert not _steady(sweep, n // 2, fs)
    assert not _steady(coda, n // 2, fs)
