"""The RK4 with the mechanics unrolled for the model's shape (`reduced_unrolled`) gives the
histories of the generic loop (`reduced_kernel._steps`) bit for bit: the same operations
in the same order, for every shape a diagnosis meets (coordinates 2-4, with and without
the pitch loop, quadratic dampers, a controller's own stage states), and the same NaN
from the step a model blows up."""

from __future__ import annotations

import re

import numpy as np
import pytest

from vtable.models import reduced_unrolled
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.params import presets
from vtable.runs.lab import lab_table
from vtable.runs.table import table_from_dict
from vtable.tables.lab import bare_loop

T = np.arange(3000) / 200.0
X_C = 0.02 * np.sin(2 * np.pi * 0.7 * T) + 0.004 * np.sin(2 * np.pi * 6.3 * T + 0.4)


def _both(model: ReducedModel, monkeypatch) -> tuple:
    """(unrolled, generic) histories of `model` over the test command; the first made by
    the unrolled loop (counted), the second by the generic one."""
    assert reduced_unrolled.kernel(model) is not None
    calls, simulate = [], reduced_unrolled.simulate

    def counted(*a):
        calls.append(1)
        return simulate(*a)

    with monkeypatch.context() as m:
        m.setattr(reduced_unrolled, "simulate", counted)
        fast = model.histories(T, X_C)
    assert calls == [1] and model.element.key.endswith("u")
    with monkeypatch.context() as m:
        m.setattr(reduced_unrolled, "kernel", lambda model: None)
        slow = model.histories(T, X_C)
    return fast, slow


def _same(a, b) -> None:
    for x, y in zip((a.q, a.qd, a.qdd, a.force, a.p_l), (b.q, b.qd, b.qdd, b.force, b.p_l),
                    strict=True):
        assert x.shape == y.shape
        assert np.array_equal(x, y, equal_nan=True)


@pytest.mark.parametrize("effects,shape", [
    ({"actuator_friction": {"friction": 3.0}}, (2, 0)),
    ({"actuator_friction": {"friction": 3.0}, "pitch_flexibility": {}}, (3, 1)),
    ({"actuator_friction": {"friction": 3.0}, "pitch_flexibility": {},
      "platen_resonator": {}}, (4, 1)),
    ({"amplitude_dependent_damping": {}}, (2, 0)),
    ({"valve_flow_nonlinearity": {}, "force_feedback_filter": {}}, (2, 0)),
])
def test_unrolled_histories_are_the_generic_loops(effects, shape, monkeypatch):
    model = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                                 effects))
    assert not model.linear and (model.M.shape[0], model.Aw.shape[0]) == shape
    # the array `_rates` reads by index holds every number it names, in their order
    text = reduced_unrolled._source(model.element.module.__name__, *shape)
    names = " ".join(ln.split("# c:", 1)[1] for ln in text.splitlines() if "# c:" in ln)
    used = {int(k) for k in re.findall(r"\bc\[(\d+)\]", text)}
    assert len(reduced_unrolled.constants(model)) == len(names.split()) == len(used) \
        == max(used) + 1
    fast, slow = _both(model, monkeypatch)
    _same(fast, slow)
    assert np.ptp(fast.q[:, 0]) > 0.01  # it moved: the table follows the 20 mm command


def test_a_controllers_own_states_step_the_same(monkeypatch):
    """LNEC's table under its PID controller: the control stage's states ride in the servo
    states' array the unrolled loop hands to the stage code."""
    vt = lab_table(table_from_dict({"preset": "lnec-st1d", "controller": {
        "kind": "pid", "displacement_gain_v_per_m": 129.93, "p": 2.5, "i_per_s": 0.5}}))
    model = ReducedModel(Physics(bare_loop(vt), presets.specimen("sdof_frame"),
                                 {"actuator_friction": {"friction": 1.0}}), vt)
    assert model.element.module.NS > 1
    fast, slow = _both(model, monkeypatch)
    _same(fast, slow)


def test_a_replaced_matrix_is_read_again_and_a_blow_up_ends_in_the_same_nan(monkeypatch):
    model = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                                 {"actuator_friction": {"friction": 3.0}}))
    before = model.histories(T, X_C)
    model.K = -model.K  # a mechanical system that diverges whatever the servo does
    fast, slow = _both(model, monkeypatch)
    _same(fast, slow)
    bad = np.flatnonzero(~np.isfinite(fast.q[:, 0]))
    assert len(bad) > 0 and 0 < bad[0] < len(T) - 1
    assert np.all(np.isfinite(before.q))


def test_force_elements_keep_the_generic_loop():
    model = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                                 {"storey_yield": {}}))
    assert model.elem is not None and reduced_unrolled.kernel(model) is None


def test_a_kernel_that_does_not_compile_leaves_the_shape_to_the_generic_loop(monkeypatch):
    """A stage law that allocates does not compile in the unrolled loop (no reference
    counting): that stage set and shape are stepped by the generic loop from then on, with
    the same histories, and the stage set is not moved to the counted loop for it."""
    import numba

    model = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                                 {"actuator_friction": {"friction": 2.5}}))
    ref = model.histories(T, X_C)

    def fails(*a):
        raise numba.core.errors.TypingError("a law that allocates")

    monkeypatch.setattr(reduced_unrolled, "simulate", fails)
    monkeypatch.setattr(reduced_unrolled, "_KERNELS", dict(reduced_unrolled._KERNELS))
    again = model.histories(T, X_C)
    _same(again, ref)
    assert reduced_unrolled.kernel(model) is None and model.element.key.endswith("u")
