"""Issue 21, hysteretic storeys: the `[specimen.hysteresis]` declaration, and the Bouc–Wen
storeys in the reduced model and the virtual table — against each other on runs that
yield (≤ 2 % NRMS), and against an independent integration of the Bouc–Wen equation driven
by the model's own drift (scipy's solve_ivp, not vtable's law)."""

from __future__ import annotations

import dataclasses
import functools
import re
from pathlib import Path

import numpy as np
import pytest
import scipy.integrate

from vtable.errors import VtableError
from vtable.params import presets
from vtable.params.specimen import specimen_from_dict

IN, KIP = 0.0254, 4448.2216152605

FRAME = {"kind": "sdof", "weight_kip": 68.0, "height_in": 219.0, "frequency_hz": 2.87,
         "damping": 0.01, "hysteresis": {"yield_drift_in": 0.3, "post_yield_ratio": 0.1}}
BUILDING = {"kind": "shear_building", "weights_kip": [20.0, 20.0, 20.0],
            "heights_in": [80.0, 150.0, 219.0], "frequencies_hz": [2.0, 6.0, 9.5],
            "damping": 0.02,
            "hysteresis": {"storeys": [2], "yield_drift_in": 0.15, "post_yield_ratio": 0.05,
                           "n": 3.0}}


def nrms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2) / np.mean(b**2)))


@functools.cache
def played(kind: str, hysteretic: bool = True):
    """(specimen, the virtual table's run, the reduced model's prediction) under El Centro
    (2 in, its first 10 s) on the standard EERC table."""
    from vtable.models.reduced import ReducedModel
    from vtable.signals import make_command
    from vtable.sim.run import simulate, standard_physics

    spec = specimen_from_dict(FRAME if kind == "frame" else BUILDING)
    if not hysteretic:
        spec = dataclasses.replace(spec, hysteresis=None)
    ph = standard_physics(spec)
    cmd = make_command("earthquake", record="elcentro", peak_in=2.0, duration=10.0)
    run = simulate(ph, cmd, 200.0)
    return spec, run, ReducedModel(ph).simulate(run.time, run.channels["h_span"])


def test_the_declaration_reads_converts_and_round_trips():
    spec = specimen_from_dict(BUILDING)
    h = spec.hysteresis
    assert h.storeys == (2,) and h.of_storey(1, 1e7) is None
    assert h.of_storey(2, 1e7) == (pytest.approx(0.15 * IN), 0.05)
    assert (h.n, h.beta) == (3.0, 0.5)
    assert specimen_from_dict(spec.to_dict()) == spec
    # a strength instead of a drift, kept as declared: u_y = V_y / k_s with the model's
    # stiffness (k_s = m ω², eq 3.8: 57.3 kip/in for the declared frame)
    frame = specimen_from_dict({**FRAME, "hysteresis": {"yield_shear_kip": 10.0,
                                                        "post_yield_ratio": 0.1}})
    k = (68.0 * KIP / 9.80665) * (2 * np.pi * 2.87) ** 2
    assert frame.stiffness == pytest.approx(k)
    u_y = frame.hysteresis.of_storey(1, frame.stiffness)[0]
    assert u_y == pytest.approx(10.0 * KIP / k) and u_y / IN == pytest.approx(0.1746, abs=1e-3)
    assert frame.to_dict()["hysteresis"]["yield_shear_kip"] == [pytest.approx(10.0)]
    assert specimen_from_dict(frame.to_dict()) == frame
    bad = [({"yield_drift": 1.0, "post_yield_ratio": 0.1}, "did you mean 'yield_drift_in'"),
           ({"yield_drift_in": 1.0}, "post_yield_ratio"),
           ({"yield_drift_in": [1.0, 2.0], "post_yield_ratio": 0.1}, "2 values for 1 storeys"),
           ({"storeys": [2], "yield_drift_in": 1.0, "post_yield_ratio": 0.1}, "1..1"),
           ({"yield_drift_in": 1.0, "post_yield_ratio": 1.5}, "<= 1"),
           ({"yield_drift_in": 1.0, "post_yield_ratio": 0.1, "n": 0.5}, ">= 1")]
    for d, msg in bad:
        with pytest.raises(VtableError, match=msg.replace("(", r"\(").replace(")", r"\)")):
            specimen_from_dict({**FRAME, "hysteresis": d})
    with pytest.raises(VtableError, match="only a sdof or shear_building"):
        specimen_from_dict({"kind": "rigid", "weight_kip": 70.0, "height_in": 40.0,
                            "hysteresis": {"yield_drift_in": 1.0, "post_yield_ratio": 0.1}})


@pytest.mark.parametrize("kind", ["frame", "building"])
def test_the_reduced_model_and_the_virtual_table_agree_on_a_run_that_yields(kind):
    """Issue 21's acceptance: ≤ 2 % NRMS between the two models' hysteretic storeys (the
    drift, the shear and the table's own channels), on a run whose storey goes well past
    its yield drift."""
    spec, run, pred = played(kind)
    h = spec.hysteresis
    k = h.storeys[0]
    drift = run.channels[f"floor{k}_drift"]
    # it yields: ductility 2.50 (the first 10 s scaled as the whole record is, 1.03 g; it was
    # 2.6 when the cut alone was scaled to 2 in, 1.08 g)
    assert np.max(np.abs(drift)) > 2.4 * h.yield_drift[0]
    for ch in (f"floor{k}_drift", f"floor{k}_shear", "avg_hdisp", "avg_hacc", "acc_n_ne"):
        assert nrms(pred[ch], run.channels[ch]) < 0.02, (ch, nrms(pred[ch], run.channels[ch]))
    assert run.units[f"floor{k}_drift"] == "in" and run.units[f"floor{k}_shear"] == "kip"


def test_the_storey_shear_follows_an_independent_bouc_wen_integration():
    """The frame's storey shear −m a_top (the virtual table's accelerometer) against
    α k u + (1 − α) k u_y z + c u̇ with z integrated here by solve_ivp from the virtual
    table's own drift: within 2 % NRMS; and the loop reaches the strength, not k u."""
    spec, run, _ = played("frame")
    h = spec.hysteresis
    u_y, alpha = h.of_storey(1, spec.stiffness)
    t = run.time
    u = run.channels["floor1_drift"]
    v = np.gradient(u, t)

    def zdot(tt, z):
        vv = np.interp(tt, t, v)
        a = abs(z[0])
        return [(vv - h.beta * abs(vv) * a ** (h.n - 1) * z[0] - h.gamma * vv * a**h.n) / u_y]

    z = scipy.integrate.solve_ivp(zdot, (t[0], t[-1]), [0.0], t_eval=t, max_step=1e-3,
                                  rtol=1e-8, atol=1e-10).y[0]
    k, c = spec.stiffness, spec.damping_coefficient
    V = alpha * k * u + (1 - alpha) * k * u_y * z + c * v
    shear = run.channels["floor1_shear"]
    assert nrms(shear, V) < 0.02, nrms(shear, V)
    strength = (alpha * k * np.max(np.abs(u)) + (1 - alpha) * k * u_y) / KIP
    assert np.max(np.abs(shear)) / KIP == pytest.approx(strength, rel=0.05)
    assert np.max(np.abs(shear)) < 0.5 * k * np.max(np.abs(u))  # far below the elastic k u


def test_post_yield_ratio_one_is_the_elastic_storey():
    """α = 1 leaves nothing to the hysteretic part: the elastic response, to 1e-6."""
    from vtable.models.reduced import ReducedModel
    from vtable.sim.run import standard_physics

    spec = specimen_from_dict({**FRAME, "hysteresis": {"yield_drift_in": 0.3,
                                                       "post_yield_ratio": 1.0}})
    _, run, elastic = played("frame", hysteretic=False)
    pred = ReducedModel(standard_physics(spec)).simulate(run.time, run.channels["h_span"])
    assert nrms(pred["pot_n_sw"], elastic["pot_n_sw"]) < 1e-6


@functools.cache
def truth_campaign(tmp: str):
    """The Table 9.2 frame yielding at 0.3 in (α 0.1) on the truth's pitching table: two
    random runs (0.1 and 1 in) and El Centro (2 in), 20 s, 2 % noise, the declaration off
    (frequency, damping and the yield drift, `truth.perturb`)."""
    import truth

    spec = truth.sdof(68.0, 219.0, 2.87, 0.01, hysteresis={"yield_drift_in": 0.3,
                                                            "post_yield_ratio": 0.1})
    paths = truth.campaign(f"{tmp}/yield", truth.eerc_table(pitch="hybrid"), spec,
                           truth.perturb(spec, seed=5), fs=200.0, duration_s=20.0, seed=3,
                           quake_peak_in=2.0)
    elastic = []
    for p in paths:  # the same runs declared without the hysteresis
        q = p.with_name(p.stem + "_elastic.toml")
        q.write_text(re.sub(r"\[specimen\.hysteresis\]\n(?:[^\[\n].*\n|\n)*", "",
                            p.read_text()))
        assert "hysteresis" in p.read_text() and "hysteresis" not in q.read_text()
        (q.with_suffix(".csv")).write_bytes(p.with_suffix(".csv").read_bytes())
        elastic.append(q)
    return [str(p) for p in paths], [str(q) for q in elastic]


def test_the_declared_hysteresis_explains_an_independent_truths_yielding_runs(
        tmp_path_factory):
    """On the truth's campaign (its own Bouc–Wen, RK4 at 0.25 ms), vtable's model with the
    run's declared hysteresis (yield drift off by up to 10 %) fits the held-out data near
    the noise floor; declared elastic, the same model misses by several times more."""
    from vtable import verbs

    tmp = tmp_path_factory.mktemp("truth_yield")
    yielding, elastic = truth_campaign(str(tmp))
    with_h = verbs.compare(yielding, ["pitch_flexibility"], report=str(tmp / "report.html"))
    without = verbs.compare(elastic, ["pitch_flexibility"])
    print(f"with the declared hysteresis {with_h.error:.4f}, declared elastic "
          f"{without.error:.4f}, noise floor {with_h.noise_floor:.4f}")
    assert with_h.error < 2.0 * with_h.noise_floor, (with_h.error, with_h.noise_floor)
    assert without.error > 3 * with_h.error, (without.error, with_h.error)
    # the report draws each run's storey loop, measured and the model's (one figure a run)
    html = (tmp / "report.html").read_text()
    loops = html.split("id='loops'")[1].split("<h2>")[0]
    assert loops.count("data:image/png;base64,") == len(yielding), loops[:200]


def test_an_analytical_model_of_a_yielding_specimen_says_it_is_linear(tmp_path):
    """The analytical models take the storey at its initial stiffness, and their title
    says so (the declaration is not silently dropped): the same modes as the elastic
    frame's."""
    from vtable.analytic import configs

    text = """model = "hybrid"
[specimen]
kind = "sdof"
weight_kip = 68.0
height_in = 219.0
frequency_hz = 2.87
damping = 0.01
%s
[open_loop]
f_o_hz = 9.6
xi_o = 0.606
k_o_per_s = 29.5
[rocking]
k_theta_lb_in_per_rad = 2.22e10
c_theta_lb_in_s_per_rad = 3.7e8
"""
    (tmp_path / "y.toml").write_text(text % "[specimen.hysteresis]\nyield_drift_in = 0.3\n"
                                     "post_yield_ratio = 0.1")
    (tmp_path / "e.toml").write_text(text % "")
    y, e = configs.load(str(tmp_path / "y.toml")), configs.load(str(tmp_path / "e.toml"))
    assert "initial stiffness" in y.title and "initial stiffness" not in e.title
    assert np.allclose(np.sort_complex(y.poles()), np.sort_complex(e.poles()))


@functools.cache
def yielding_building(tmp: str, storeys: tuple[int, ...] = (2,)) -> list[str]:
    """A 3-storey building whose `storeys` yield at 0.15 in (α 0.05) on the truth's
    pitching table, declared elastic and off (`truth.perturb`): two random runs and El
    Centro (2 in), 10 s, 2 % noise."""
    import truth

    hyst = {"storeys": list(storeys), "yield_drift_in": 0.15, "post_yield_ratio": 0.05}
    spec = truth.building([20.0, 20.0, 20.0], [80.0, 150.0, 219.0],
                          frequencies_hz=[2.0, 6.0, 9.5], xi=0.02, hysteresis=hyst)
    elastic = truth.building([20.0, 20.0, 20.0], [80.0, 150.0, 219.0],
                             frequencies_hz=[2.0, 6.0, 9.5], xi=0.02)
    paths = truth.campaign(f"{tmp}/building{''.join(map(str, storeys))}",
                           truth.eerc_table(pitch="hybrid"), spec,
                           truth.perturb(elastic, seed=5), fs=200.0, duration_s=10.0,
                           seed=3, quake_peak_in=2.0)
    return [str(p) for p in paths]


#: the catalog the yielding diagnoses choose from: the storey, the table's own pitch, and
#: the effect that also makes the structure's response amplitude-dependent (the rival a
#: yield must beat; the full catalog's run is in docs/effects.md)
RIVALS = ["storey_yield", "pitch_flexibility", "amplitude_dependent_damping"]


@pytest.mark.parametrize("case", ["frame", "building", "building, two storeys",
                                  "building, upper two storeys"])
def test_diagnose_finds_the_storey_that_yields_and_its_yield_drift(case, tmp_path_factory):
    """Issue 21: on the independent truth's campaigns declared elastic (the frame yielding
    at 0.3 in, α 0.1; the building's 2nd storey at 0.15 in, α 0.05; its 1st and 2nd
    alike; its 2nd and 3rd, the best single storey's run grown), `diagnose` adds
    storey_yield on the right storeys with the yield drift within 20 % (the frame beating
    amplitude-dependent damping), and ends within 2x the noise floor. The building is
    given the table's pitch (`--with pitch_flexibility`): asked to find both, the diagnosis
    takes the storey first and cannot add the pitch after (a limit of its forward
    selection)."""
    from vtable import verbs

    tmp = str(tmp_path_factory.mktemp("yield"))
    storeys = {"frame": (1,), "building": (2,), "building, two storeys": (1, 2),
               "building, upper two storeys": (2, 3)}[case]
    paths = truth_campaign(tmp)[1] if case == "frame" else yielding_building(tmp, storeys)
    if case == "frame":
        d = verbs.diagnose(paths, catalog=RIVALS)
    else:  # the storeys among three are the point here; the frame meets the rival
        d = verbs.diagnose(paths, with_=["pitch_flexibility"], catalog=["storey_yield"])
    u_y, alpha = (0.3, 0.1) if case == "frame" else (0.15, 0.05)
    storey = storeys[0]
    assert "storey_yield" in d.final_effects, d.verdict
    p = d.final.effects["storey_yield"]
    print(case, p, d.final_error, d.noise_floor)
    assert (p["storey"], p["storeys"]) == (storey, len(storeys)), p
    assert p["yield_drift"] == pytest.approx(u_y, rel=0.2), p
    assert p["post_yield_ratio"] == pytest.approx(alpha, abs=0.05), p
    assert d.unexplained is None and d.final_error < 2 * d.noise_floor, d.verdict
    # the .rrd draws each storey's loop, measured and modelled (issue 21, "see it")
    from vtable.viz.diagnosis_rerun import log_diagnosis, read_blueprint_views
    from vtable.viz.rerun_scene import read_rrd

    rrd = log_diagnosis(d, f"{tmp}/d.rrd")
    ents = [str(e) for e in read_rrd(rrd)]
    assert any(e.endswith(f"loops/storey{storey}/model") for e in ents), ents
    assert any(v.get("class") == "2D" and v.get("name", "").startswith(f"storey {storey}:")
               for v in read_blueprint_views(rrd))


def test_fixed_base_yielding_sdof_at_post_yield_ratio_one_is_the_linear_frame():
    """The ductility sweep's fixed-base specimen (Bouc–Wen, scipy's RK45) with α = 1 is the
    elastic frame: its peak drift equals §9.4's fixed-base state-space model's (exact
    discretization, `interaction.peak_response`) to 0.5 %."""
    import dataclasses

    from vtable.params.hysteresis import parse_hysteresis
    from vtable.signals.processing import process_record
    from vtable.signals.records import load_record
    from vtable.studies import interaction as ia
    from vtable.studies import yielding

    frame = presets.specimen("sdof_frame")
    spec = dataclasses.replace(frame, hysteresis=parse_hysteresis(
        {"yield_drift_in": 0.3, "post_yield_ratio": 1.0}, 1, "h"))
    cmd = process_record(load_record("elcentro"))
    u = yielding.fixed_base_drift(spec, cmd.time, cmd.acceleration)
    lin = ia.peak_response([ia.five_models(frame)["fixed base"]], cmd.acceleration, cmd.dt)[0]
    assert np.max(np.abs(u)) == pytest.approx(lin, rel=5e-3)


def test_ductility_on_the_table_matches_the_virtual_table():
    """`assess`'s ductility on the table (the reduced model) at the frame's own period
    against the multibody virtual table playing the same command (El Centro's first 10 s
    at 2 in): within 3 %; and fixed base and table differ there while at 2 s, where the
    table barely moves the specimen's period, they agree within 5 %."""
    from vtable.signals.command import make_command
    from vtable.sim.experiment import load_specimen, run_experiment
    from vtable.studies import yielding

    spec = load_specimen(str(Path(__file__).parents[2] / "examples" / "yielding_frame.toml"))
    cmd = make_command("earthquake", peak_in=2.0, duration=10.0)
    acc = np.gradient(np.gradient(cmd.x, cmd.t), cmd.t)
    T_s = 1.0 / spec.frequency
    y = yielding.sweep(spec, cmd.t, cmd.x, acc, [T_s, 2.0])
    u_y = spec.hysteresis.of_storey(1, spec.stiffness)[0]
    exp = run_experiment(spec, cmd)
    mu_virtual = np.max(np.abs(exp.run.channels["floor1_drift"])) / u_y
    print(y.ductility_fixed, y.ductility_table, mu_virtual)
    assert y.ductility_table[0] == pytest.approx(mu_virtual, rel=0.03)
    assert y.ductility_table[1] == pytest.approx(y.ductility_fixed[1], rel=0.05)
    assert y.held == "yield drift"


def test_a_yield_drift_that_no_run_reaches_blocks_the_candidate():
    """Selection criterion 5 (`Effect.unseen`): a storey_yield fitted with a yield drift
    beyond the storey's largest predicted drift (an elastic specimen's smooth softening
    bought with an extrapolated u_y, as on the scorecard's pump_drop case) is flagged on
    its own parameter, which blocks it; one the runs reach is not."""
    from vtable.diagnose.result import Candidate
    from vtable.effects import get

    e = get("storey_yield")
    pred = {"r1": {"floor1_drift": np.array([0.0, 0.01, -0.02]), "floor2_drift": np.ones(3)},
            "r2": {"floor1_drift": np.array([0.005])}}  # m: storey 1 peaks at 0.787 in
    assert e.unseen({"storey": 1.0, "yield_drift": 0.7, "post_yield_ratio": 0.1}, pred) is None
    why = e.unseen({"storey": 1.0, "yield_drift": 0.8, "post_yield_ratio": 0.1}, pred)
    assert why == ("storey_yield.yield_drift 0.8 in is never reached (storey 1's largest "
                   "drift in the model's prediction is 0.787 in): no run shows it yield")
    assert e.unseen({"storey": 2.0, "yield_drift": 20.0, "post_yield_ratio": 0.1}, pred) is None
    # storeys 1-2: the larger of their drifts (storey 2's, 1 m) reaches 20 in
    assert e.unseen({"storey": 1.0, "storeys": 2.0, "yield_drift": 20.0,
                     "post_yield_ratio": 0.1}, pred) is None
    assert "storeys 1-2's largest drift in the model's prediction is 39.4 in" in e.unseen(
        {"storey": 1.0, "storeys": 2.0, "yield_drift": 40.0, "post_yield_ratio": 0.1}, pred)
    c = Candidate("storey_yield", {}, 0.0, 0.0, "", 3, None, [why], None)
    assert c.blocking == [why]


def test_storey_yield_grows_the_best_run_of_storeys_and_builds_them():
    """`storey_yield`'s choices on a 3-storey building: each storey alone first, then the
    best run so far grown by the storey below and the one above (within the building);
    storeys 2-3 put a Bouc–Wen element on each of the two storeys' drifts, with the
    storey's own elastic stiffness; a run beyond the building, or over a storey declared
    yielding, is a one-line error naming it."""
    from vtable.analytic.structure import storey_stiffnesses_of
    from vtable.effects import get
    from vtable.models.physics import Physics, nominal_open_loop
    from vtable.models.reduced import ReducedModel
    from vtable.params.hysteresis import parse_hysteresis

    e = get("storey_yield")
    spec = specimen_from_dict({"kind": "shear_building", "weights_kip": [25.0, 25.0, 25.0],
                               "heights_in": [110.0, 160.0, 210.0],
                               "frequencies_hz": [2.87, 7.5, 11.1], "damping": 0.02})
    def runs(tried):
        return [(c["storey"], c["storeys"]) for c in e.choices(spec, [
            ({"storey": k, "storeys": j}, cost) for (k, j), cost in tried.items()])]

    assert runs({}) == [(1, 1), (2, 1), (3, 1)]
    singles = {(1, 1): 3.0, (2, 1): 1.0, (3, 1): 2.0}
    assert runs(singles) == [(1, 2), (2, 2)]  # storey 2 best: with the 1st, with the 3rd
    assert runs({**singles, (1, 2): 0.5, (2, 2): 0.8}) == [(1, 3)]
    assert runs({(1, 1): 1.0, (2, 1): 2.0, (3, 1): 3.0}) == [(1, 2)]
    assert e.choices(presets.specimen("sdof_frame")) == [{"storey": 1, "storeys": 1}]
    assert e.choices(presets.specimen("sdof_frame"), [({"storey": 1, "storeys": 1}, 1.0)]) \
        == []
    ph = Physics(nominal_open_loop(), spec, {}).with_effect(
        "storey_yield", {"storey": 2, "storeys": 2, "yield_drift": 0.2})
    m = ReducedModel(ph, kernels=False)
    els = m.assembly.elements
    assert [el.a for el in els] == ["x_s2", "x_s3"]
    k = storey_stiffnesses_of(spec)
    assert [dict(zip(el.names, el.params, strict=True))["k"] for el in els] == \
        pytest.approx([k[1], k[2]], rel=1e-12)
    with pytest.raises(VtableError, match=r"^storey_yield: storeys 2-4, but the specimen "
                                          r"has 3 storeys$"):
        ReducedModel(ph.with_effect("storey_yield", {"storey": 2, "storeys": 3}), kernels=False)
    declared = dataclasses.replace(spec, hysteresis=parse_hysteresis(
        {"storeys": [3], "yield_drift_in": 0.3, "post_yield_ratio": 0.1}, 3, "h"))
    with pytest.raises(VtableError, match="storey 3 is declared yielding already"):
        ReducedModel(dataclasses.replace(ph, specimen=declared), kernels=False)


def test_a_candidates_fit_chooses_its_own_storeys_and_keeps_the_models(monkeypatch,
                                                                      tmp_path):
    """Which storeys yield is chosen when `storey_yield` is the candidate or when a model is
    fitted afresh: each storey alone, then the best run grown while it fits better (here
    storeys 1-2 best: five of the six runs fitted, 1-2 kept); a later candidate's fit, and
    a refit of a fitted model (`choose=False`: a backward step, the widened bounds, a state
    per run; `choose=[...]`: a drive's refit with effects added, which chooses theirs
    only), keep the storeys the model holds (they were chosen when it was added;
    re-choosing them multiplied every later candidate's fit)."""
    from vtable.diagnose.campaign import Campaign
    from vtable.diagnose.model import TableModel
    from vtable.models.physics import Physics, nominal_open_loop
    from vtable.runs import read_run

    c = Campaign.of([read_run(p) for p in yielding_building(str(tmp_path))])
    base = Physics(nominal_open_loop(c.table), c.specimen, {})
    held = base.with_effect("storey_yield", {"storey": 2, "storeys": 1})
    tried = []

    seeds = []

    def fit_from(self, campaign, start):  # the combination tried, no fit: 1-2 costs least
        p = start.effects["storey_yield"]
        tried.append((p["storey"], p["storeys"]))
        seeds.append(self.seed)
        self.cost_ = abs(p["storey"] - 1) + abs(p["storeys"] - 2)
        self.physics_ = start
        return self

    monkeypatch.setattr(TableModel, "_fit_from", fit_from)
    grown = [(1, 1), (2, 1), (3, 1), (1, 2), (1, 3)]
    # the candidate's own fit: a later proposal won, so the first that fitted best (1 alone)
    # is fitted once more from the winner's values (`choices.fit_choices`)
    runs = [(dict(start=held, multistart="storey_yield"), [*grown, (1, 1)], (1, 2)),
            (dict(start=held.with_effect("pitch_flexibility"), multistart="pitch_flexibility"),
             [(2, 1)], (2, 1)),
            (dict(start=held), grown, (1, 2)), (dict(start=held, choose=False), [(2, 1)], (2, 1)),
            (dict(start=held, choose=["storey_yield"]), grown, (1, 2)),  # named: chosen
            (dict(start=held.with_effect("pitch_flexibility"), choose=["pitch_flexibility"]),
             [(2, 1)], (2, 1))]  # a refit adding the pitch keeps the storeys
    for kw, want, kept in runs:
        tried.clear()
        seeds.clear()
        m = TableModel(**kw).fit(c)
        p = m.physics_.effects["storey_yield"]
        assert tried == want and (p["storey"], p["storeys"]) == kept, (kw, tried, p)
        again = [s for s in seeds if s is not None]
        if kw.get("multistart") == "storey_yield":  # seeded from the winner, 1-2
            assert len(again) == 1 and (again[0]["storey"], again[0]["storeys"]) == (1, 2)
        else:
            assert not again
