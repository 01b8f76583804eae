"""The effect catalog: each effect is the same physics in the reduced model and on the
virtual table (MuJoCo + controllers)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import HIDDEN, campaign_commands

from vtable.effects import load_file
from vtable.effects.registry import get, names
from vtable.errors import VtableError
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.params import presets
from vtable.sim import simulate


def test_catalog_has_the_spec_names():
    spec = ("pitch_flexibility force_feedback_filter valve_flow_nonlinearity actuator_friction "
            "flow_saturation valve_dynamics oil_column_air amplitude_dependent_damping "
            "foundation_compliance sensor_filter").split()
    assert set(spec) <= set(names())
    for e in map(get, names()):
        assert e.physics and e.section and e.signature and e.params
        for p in e.params:
            assert p.lower <= p.default <= p.upper and p.unit


#: every registered effect at a visible dose: the catalog's and the README's user effects
#: (examples/swivel_backlash.py and examples/valve_overlap.py, loaded as a user would)
EXAMPLES = [Path(__file__).resolve().parents[2] / "examples" / f
            for f in ("swivel_backlash.py", "valve_overlap.py")]
DOSES = {**HIDDEN, "platen_resonator": {"m_r": 20.0, "f_r": 12.0, "xi_r": 0.03},
         "swivel_backlash": {"gap": 0.005}, "valve_overlap": {"overlap": 0.5},
         "storey_yield": {"storey": 1, "yield_drift": 0.1, "post_yield_ratio": 0.1},
         "sensor_mount": {"f_m": 17.0, "zeta_m": 0.09, "f_c": 30.0},
         "specimen_degradation": {"delta": 0.01, "exponent": 0.7},
         "sensor_offset": {"offset": 0.01}}


@pytest.fixture
def examples():
    """The README's user effects loaded (conftest's catalog_as_shipped unloads them)."""
    return [n for f in EXAMPLES for n in load_file(f)]


def test_the_doses_cover_every_registered_effect(examples):
    assert examples == ["swivel_backlash", "valve_overlap"]
    assert set(DOSES) == set(names())


@pytest.mark.parametrize("name", list(DOSES))
def test_reduced_model_agrees_with_the_virtual_table(name, examples):
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"), {name: DOSES[name]})
    random, _, quake = campaign_commands()
    for cmd in (random, quake):
        run = simulate(ph, cmd)
        pred = ReducedModel(ph).predict(run)
        # an SDOF frame's floor 1 is its top mass; the table writes floors for buildings
        assert set(pred) - set(run.channels) == {"floor1_acc", "floor1_disp", "floor1_drift",
                                                 "floor1_shear"}  # storeys: a yielding run
        assert np.array_equal(pred["floor1_acc"], pred["acc_n_ne"])
        assert np.array_equal(pred["floor1_disp"], pred["pot_n_sw"])
        for ch, yhat in pred.items():
            if ch.startswith("floor"):
                continue
            y = run.channel(ch)
            if not np.any(y):
                continue
            err = np.sqrt(np.mean((yhat - y) ** 2) / np.mean(y**2))
            # h_vel is the actuators' velocity: with backlash, the piston's, which rattles
            # across the gap at the contact's stiffness, resolved differently by the two
            # integrators (its displacement, and the platen's motion, agree within 2 %)
            tol = 0.06 if (name, ch) == ("swivel_backlash", "h_vel") else 0.02
            assert err < tol, (name, cmd.name, ch, err)


#: a 3-storey shear building: 3 x 25 kip at 110/160/210 in, storeys 120/100/80 kip/in
BUILDING = {"kind": "shear_building", "weights_kip": [25.0, 25.0, 25.0],
            "heights_in": [110.0, 160.0, 210.0], "stiffnesses_kip_per_in": [120.0, 100.0, 80.0],
            "damping": 0.02}


@pytest.mark.parametrize("effects", [{}, {"pitch_flexibility": {}}])
def test_reduced_model_predicts_a_buildings_floors_as_the_virtual_table(effects):
    """floorK = x_t + h_K θ + Σ_{i≤K} x_s,i (reduced model) against the MuJoCo table's
    sensors on each storey body; with pitch_flexibility the h_K θ term is exercised."""
    from vtable.params.specimen import specimen_from_dict

    ph = Physics(nominal_open_loop(), specimen_from_dict(BUILDING, "building"), effects)
    random, _, quake = campaign_commands()
    floors = {f"floor{k}_{w}" for k in (1, 2, 3) for w in ("acc", "disp")}
    for cmd in (random, quake):
        run = simulate(ph, cmd)
        pred = ReducedModel(ph).predict(run)
        assert floors <= set(run.channels) and floors <= set(pred)
        assert not any(c.startswith("floor4") for c in (*run.channels, *pred))
        rms = {}
        for ch in sorted(floors):
            y = run.channel(ch)
            rms[ch] = np.sqrt(np.mean(y**2))
            err = np.sqrt(np.mean((pred[ch] - y) ** 2)) / rms[ch]
            assert err < 0.02, (effects, cmd.name, ch, err)
        # the floors are distinct signals, growing upwards (first mode)
        assert rms["floor1_disp"] < rms["floor2_disp"] < rms["floor3_disp"]
        assert np.sqrt(np.mean((run.channel("floor1_acc") - run.channel("floor3_acc")) ** 2)) \
            > 0.2 * rms["floor3_acc"]
        # the top floor is the top-mass instrument (its corner: second order in θ apart)
        assert np.allclose(run.channel("floor3_acc"), run.channel("acc_n_ne"), rtol=0,
                           atol=1e-4 * rms["floor3_acc"])


def test_effect_parameters_are_checked():
    with pytest.raises(VtableError, match=r"v_max = 100 in/s is outside \[1, 60\]"):
        Physics(nominal_open_loop(), presets.specimen("none"), {"flow_saturation":
                                                                {"v_max": 100.0}})
    with pytest.raises(VtableError, match="unknown effect 'gremlins'"):
        Physics(nominal_open_loop(), presets.specimen("none"), {"gremlins": {}})


@pytest.mark.parametrize("fs", [256.0, 1000.0, 150.0])
def test_virtual_runs_at_other_rates_and_the_reduced_model_follows(fs):
    """simulate(rate=...) steps the table at 1/(k·fs); the reduced model integrates
    at a step dividing the run's (≤ 2.5 ms) and agrees as it does at 200 Hz."""
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                 {"valve_dynamics": HIDDEN["valve_dynamics"], "sensor_filter": {}})
    random, _, _ = campaign_commands()
    run = simulate(ph, random, rate=fs)
    assert run.fs == pytest.approx(fs, rel=1e-12)
    assert run.duration == pytest.approx(random.t[-1] - random.t[0], abs=1.0 / fs)
    pred = ReducedModel(ph).predict(run)
    for ch in ("avg_hdisp", "avg_hacc", "h1_force", "acc_n_ne"):
        y = run.channel(ch)
        err = np.sqrt(np.mean((pred[ch] - y) ** 2) / np.mean(y**2))
        assert err < 0.02, (fs, ch, err)


def test_virtual_run_refuses_a_bad_rate():
    ph = Physics(nominal_open_loop(), presets.specimen("none"))
    with pytest.raises(VtableError, match=r"output rate -5 Hz: expected a positive rate"):
        simulate(ph, campaign_commands()[0], rate=-5.0)


def test_both_models_implement_the_whole_assembly_vocabulary():
    """`register` checks an effect's verbs against `Assembly` alone, so both models must
    realise every verb of it, with the same arguments."""
    import inspect

    from vtable.effects.base import Assembly
    from vtable.models.reduced import ReducedAssembly
    from vtable.models.virtual import VirtualAssembly

    verbs = {k for k in vars(Assembly) if not k.startswith("_") and callable(vars(Assembly)[k])}
    assert {"add_stage", "add_dof", "add_spring", "add_force", "unlock", "set_rocking",
            "insert_at_actuators", "add_storey_force", "add_output_filter"} <= verbs
    for cls in (ReducedAssembly, VirtualAssembly):
        for v in verbs:
            assert callable(getattr(cls, v, None)), f"{cls.__name__} lacks {v}"
            want = list(inspect.signature(getattr(Assembly, v)).parameters)
            assert list(inspect.signature(getattr(cls, v)).parameters) == want, (cls, v)


def test_every_catalog_effect_applies_on_a_table_with_its_own_valve_lag():
    """LNEC's table declares its valve's 24.6 ms lag: every catalog effect but the pitch's
    (the platen cannot pitch) builds in the reduced model (valve_dynamics was refused
    there as a stage added twice; it is a further lag in series: x_t/x_c's phase at 10 Hz
    falls by about atan(2π 10 τ))."""
    import math

    from vtable.effects import BUILT_IN
    from vtable.models.physics import Physics
    from vtable.models.reduced import ReducedModel
    from vtable.params.specimen import NoSpecimen
    from vtable.runs.lab import lab_table
    from vtable.runs.table import table_from_dict
    from vtable.tables.lab import bare_loop

    t = lab_table(table_from_dict({"preset": "lnec-st1d"}))
    vt = t
    from vtable.errors import VtableError
    built = []
    for name in BUILT_IN:
        try:
            ReducedModel(Physics(bare_loop(t), NoSpecimen(), {name: {}}), vt)
            built.append(name)
        except VtableError as e:  # a physical refusal (no pitch on this table, no storey
            # on a bare one), said
            assert "no pitch motion" in str(e) or "has no storeys" in str(e), (name, str(e))
    # refused on a bare uniaxial table: the pitch, the yielding storey, the degrading one
    assert "valve_dynamics" in built and len(built) == len(BUILT_IN) - 3

    def phase_10hz(effects):
        m = ReducedModel(Physics(bare_loop(t), NoSpecimen(), effects), vt)
        A, B = m._linear[0], m._linear[1]
        c = np.zeros(A.shape[0])
        c[:m.M.shape[0]] = m.ax
        h = c @ np.linalg.solve(2j * math.pi * 10.0 * np.eye(len(A)) - A, B)
        return np.angle(h)

    tau = 0.002
    drop = phase_10hz({}) - phase_10hz({"valve_dynamics": {"tau": tau}})
    assert 0.5 * math.atan(2 * math.pi * 10 * tau) < drop < 2 * math.atan(2 * math.pi * 10 * tau)


def test_two_effects_adding_one_part_are_refused_in_one_line():
    """A user's effect that adds a reaction mass of the name foundation_compliance uses is
    refused by both models with a message (the reduced model once inverted a singular
    mass matrix: a traceback in the middle of a diagnosis)."""
    from vtable.effects import Effect, Param, register
    from vtable.params import presets
    from vtable.sim.run import setup

    class SecondFoundation(Effect):
        name = "second_foundation_test"
        physics, section, signature = "a second reaction mass", "test", "none"
        params = (Param("f_f", "Hz", 12.0, 1.0, 60.0),)

        def apply(self, m, p):
            m.add_reaction_mass("foundation", 1e4, 1e4 * (75.0 * p["f_f"])**2, 1e3)

    register(SecondFoundation())  # for this test alone (conftest.catalog_as_shipped)
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                 {"foundation_compliance": {}, "second_foundation_test": {}})
    for build in (ReducedModel, setup):
        with pytest.raises(VtableError, match=r"'foundation'.*two effects add the same part"):
            build(ph)
