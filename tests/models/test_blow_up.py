"""A model that blows up ends its histories with NaN from the step its table displacement
leaves the physical range (or stops being finite), in both integrators: the exact linear
stepping (`reduced_kernel.simulate_linear`) and the RK4 loop of a nonlinear stage set
(`_steps`)."""

from __future__ import annotations

import numpy as np
import pytest

from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.models.reduced_kernel import linear_system
from vtable.params import presets


def _unstable(effects: dict) -> ReducedModel:
    """The SDOF frame on the table with every spring's stiffness negated (a mechanical
    system that diverges whatever the servo does)."""
    m = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame"), effects))
    m.K = -m.K
    if m.linear:  # its state-space matrices are made at build: again with -K
        m._linear = linear_system(m.element.module, m.M.shape[0], m.Minv, m.K, m.C, m.c2,
                                  m.bF, m.ax, m.sp, m.T, m.Tp, m.g, m.kp, m.kv, m.Aw, m.Wq,
                                  m.Wv, m.Fw)
        m._holds = {}
    return m


@pytest.mark.parametrize("effects", [{}, {"valve_flow_nonlinearity": {}}])
def test_a_model_that_blows_up_ends_in_nan_from_there(effects):
    t = np.arange(4000) / 200.0
    x_c = 0.001 * np.sin(2 * np.pi * 1.0 * t)
    stable = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                                  effects))
    h = stable.histories(t, x_c)
    assert np.all(np.isfinite(h.q)) and np.all(np.isfinite(h.force))
    model = _unstable(effects)
    assert model.linear == (not effects)  # each integrator once
    h = model.histories(t, x_c)
    bad = np.flatnonzero(~np.isfinite(h.q[:, 0]))
    assert len(bad) > 0, "the negative springs did not blow up in 20 s"
    first = bad[0]
    assert 0 < first < len(t) - 1
    for a in (h.q, h.qd, h.qdd, h.force, h.p_l):  # every history NaN from there to the end
        assert np.all(np.isnan(a[first:])), a[first:]
        assert np.all(np.isfinite(a[:first]))  # and finite before
    # it ended where the table displacement left ±10 m (or overflowed)
    x = h.q[first - 1, 0]
    assert abs(x) > 10.0 or abs(h.q[first - 2, 0]) > 1e-3


def test_the_channels_of_histories_that_reached_infinity_are_nan_without_a_warning():
    """A fit's trial point whose coordinates overflowed before the table's left its range
    (the blow-up check reads the table's): its table and pitch accelerations +inf and
    -inf at a sample. Its channels there are NaN, without numpy's RuntimeWarning, which
    reached a user's terminal from a worker's fit with reduced.py's line (a real-size
    friction campaign, issue 31's figure 2)."""
    import warnings

    model = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                                 {"pitch_flexibility": {}}))
    t = np.arange(400) / 200.0
    h = model.histories(t, 0.001 * np.sin(2 * np.pi * t))
    x, p = model.ix["x"], model.ix["pitch"]
    Q, Qd, Qdd = h.q.copy(), h.qd.copy(), h.qdd.copy()
    Qdd[-1, x], Qdd[-1, p] = np.inf, -np.inf
    Q[-1, x], Q[-1, p] = -np.inf, np.inf
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = model._channels(Q, Qd, Qdd, h.force, h.p_l)
    assert np.isnan(out["acc_n_ne"][-1]) and np.isnan(out["pot_n_sw"][-1])
    assert np.all(np.isfinite(out["acc_n_ne"][:-1]))
    np.testing.assert_array_equal(out["acc_n_ne"][:-1],
                                  model._channels(h.q, h.qd, h.qdd, h.force,
                                                  h.p_l)["acc_n_ne"][:-1])


def test_a_structure_only_model_agrees_with_the_built_one_and_compiles_nothing(monkeypatch):
    """`ReducedModel(..., kernels=False)` (what a diagnosis asks of every candidate: can it
    be built, is it linear) says what the full build says, for every catalog effect alone
    and beside friction, without the integrators' element or the linear system (nothing
    compiled or loaded); it refuses to simulate in one line."""
    from vtable.effects.registry import default_candidates
    from vtable.errors import VtableError
    from vtable.hydraulics import compose
    from vtable.models import reduced

    real = compose.composition
    integrators = []

    def recorded(stages, extra=(), elements=()):
        if extra:
            integrators.append(extra)
        return real(stages, extra, elements)

    def refused(*a, **k):
        raise AssertionError("a structure-only model made its linear system")

    start = Physics(nominal_open_loop(), presets.specimen("sdof_frame"), {})
    seen = {True: 0, False: 0}
    for e in default_candidates():
        others = [] if e == "actuator_friction" else \
            [start.with_effect("actuator_friction").with_effect(e)]
        for ph in [start.with_effect(e), *others]:
            with monkeypatch.context() as mp:
                mp.setattr(compose, "composition", recorded)
                mp.setattr(reduced, "linear_system", refused)
                try:
                    quick = ReducedModel(ph, kernels=False)
                except VtableError as err:
                    with pytest.raises(VtableError, match=str(err)[:30]):
                        ReducedModel(ph)
                    continue
            assert not integrators, e
            assert quick.linear == ReducedModel(ph).linear, e
            seen[quick.linear] += 1
            with pytest.raises(RuntimeError, match="structure-only"):
                quick.simulate(np.arange(10) / 200.0, np.zeros(10))
    assert seen[True] >= 3 and seen[False] >= 8, seen  # both kinds were compared
