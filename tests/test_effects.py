"""The effect catalog: each effect is the same physics in the reduced model and on the
virtual table (MuJoCo + controllers)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import HIDDEN, campaign_commands

from vtable.effects import load_file
from vtable.effects.physics import Physics, nominal_open_loop
from vtable.effects.reduced import ReducedModel
from vtable.effects.registry import get, names
from vtable.effects.virtual import virtual_run
from vtable.errors import VtableError
from vtable.params import presets


def test_catalog_has_the_spec_names():
    spec = ("pitch_flexibility force_feedback_filter valve_flow_nonlinearity actuator_friction "
            "flow_saturation valve_dynamics oil_column_air amplitude_dependent_damping "
            "foundation_compliance sensor_filter").split()
    assert set(spec) <= set(names())
    for e in map(get, names()):
        assert e.physics and e.section and e.signature and e.params
        for p in e.params:
            assert p.lower <= p.default <= p.upper and p.unit


#: every registered effect at a visible dose: the catalog's and the README's user effect
#: (examples/swivel_backlash.py, loaded as a user would)
load_file(Path(__file__).resolve().parents[1] / "examples" / "swivel_backlash.py")
DOSES = {**HIDDEN, "swivel_backlash": {"gap": 0.005}}
REGISTERED = names()  # at collection: the catalog and the README's effect


def test_the_doses_cover_every_registered_effect():
    assert set(DOSES) == set(REGISTERED)


@pytest.mark.parametrize("name", list(DOSES))
def test_reduced_model_agrees_with_the_virtual_table(name):
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"), {name: DOSES[name]})
    random, _, quake = campaign_commands()
    for cmd in (random, quake):
        run = virtual_run(ph, cmd)
        pred = ReducedModel(ph).predict(run)
        for ch, yhat in pred.items():
            y = run.channel(ch)
            if not np.any(y):
                continue
            err = np.sqrt(np.mean((yhat - y) ** 2) / np.mean(y**2))
            assert err < 0.02, (name, cmd.name, ch, err)


def test_effect_parameters_are_checked():
    with pytest.raises(VtableError, match=r"v_max = 100 in/s is outside \[1, 60\]"):
        Physics(nominal_open_loop(), presets.specimen("none"), {"flow_saturation":
                                                                {"v_max": 100.0}})
    with pytest.raises(VtableError, match="unknown effect 'gremlins'"):
        Physics(nominal_open_loop(), presets.specimen("none"), {"gremlins": {}})


@pytest.mark.parametrize("fs", [256.0, 1000.0, 150.0])
def test_virtual_runs_at_other_rates_and_the_reduced_model_follows(fs):
    """virtual_run(output_fs=...) steps the table at 1/(k·fs); the reduced model integrates
    at a step dividing the run's (≤ 2.5 ms) and agrees as it does at 200 Hz."""
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                 {"valve_dynamics": HIDDEN["valve_dynamics"], "sensor_filter": {}})
    random, _, _ = campaign_commands()
    run = virtual_run(ph, random, output_fs=fs)
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
        virtual_run(ph, campaign_commands()[0], output_fs=-5.0)
