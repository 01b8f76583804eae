"""The effect catalog: each effect is the same physics in the reduced model and on the
virtual table (MuJoCo + controllers)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import HIDDEN, campaign_commands

from vtable.effects.catalog import CATALOG
from vtable.effects.physics import Physics, nominal_open_loop
from vtable.effects.reduced import ReducedModel
from vtable.effects.virtual import virtual_run
from vtable.errors import VtableError
from vtable.params import presets


def test_catalog_has_the_spec_names():
    spec = ("pitch_flexibility force_feedback_filter valve_flow_nonlinearity actuator_friction "
            "flow_saturation valve_dynamics oil_column_air amplitude_dependent_damping "
            "foundation_compliance sensor_filter").split()
    assert set(spec) <= set(CATALOG)
    for e in CATALOG.values():
        assert e.physics and e.section and e.signature and e.params
        for p in e.params:
            assert p.lower <= p.default <= p.upper and p.unit


@pytest.mark.parametrize("name", list(HIDDEN))
def test_reduced_model_agrees_with_the_virtual_table(name):
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"), {name: HIDDEN[name]})
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
