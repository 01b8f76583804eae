"""The reduced model's nonlinear element carries the catalog's stages behind flags
(`vtable.hydraulics.compose`, `switchable`): every set of them is one compiled module, and
each model's histories are those of the element compiled for its own stages alone."""

from __future__ import annotations

import numpy as np
import pytest

from vtable.effects.registry import stock_stages
from vtable.errors import VtableError
from vtable.hydraulics.stage import Stage
from vtable.models import reduced
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.models.reduced_kernel import simulate_reduced
from vtable.params import presets

#: stage sets that exercise each kind behind its flag: a force stage alone; two flow
#: stages and the feedback filter (its `fed_back` and rate); a valve lag (a state) with
#: entrained air; force elements (a yielding storey) beside friction
SETS = [("actuator_friction",),
        ("valve_flow_nonlinearity", "flow_saturation", "force_feedback_filter"),
        ("valve_dynamics", "oil_column_air"),
        ("storey_yield", "actuator_friction")]


def _model(effects: tuple[str, ...], own: bool = False) -> ReducedModel:
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"), {})
    for e in effects:
        ph = ph.with_effect(e)
    if not own:
        return ReducedModel(ph)
    real = reduced.switchable
    reduced.switchable = lambda law: ()
    try:
        return ReducedModel(ph)
    finally:
        reduced.switchable = real


def _command(n: int = 1200, fs: float = 200.0) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) / fs
    rng = np.random.default_rng(7)
    x = np.convolve(rng.standard_normal(n), np.ones(8) / 8, mode="same") * 0.01  # m
    return t, x


@pytest.mark.parametrize("effects", SETS)
def test_a_model_through_the_switched_element_is_the_model_through_its_own(effects):
    t, x = _command()
    switched, own = _model(effects), _model(effects, own=True)
    assert not switched.linear and switched.element.switchable
    assert not own.element.switchable and own.element.key != switched.element.key
    a, b = switched.histories(t, x), own.histories(t, x)
    for name in ("q", "qd", "qdd", "force", "p_l"):
        u, v = getattr(a, name), getattr(b, name)
        assert np.all(np.isfinite(v)) and np.max(np.abs(v)) > 0, name
        np.testing.assert_allclose(u, v, rtol=1e-12, atol=1e-12 * np.max(np.abs(v)),
                                   err_msg=name)


def test_every_set_of_catalog_stages_shares_one_element_and_sets_its_flags():
    keys = {}
    for effects in SETS:
        m = _model(effects)
        keys[effects] = m.element.key
        comp, own = m.element, {s.name for s, _ in m._law.stages}
        flags = m.sp[len(m.sp) - len(comp.switchable):]
        switched = [s.name for s in comp.stages if s.name in comp.switchable]
        assert switched == [s.name for s in comp.stages if s in stock_stages()]
        assert list(flags) == [1.0 if s in own else 0.0 for s in switched], effects
    with_elements = {keys[e] for e in SETS if "storey_yield" in e}
    without = {keys[e] for e in SETS if "storey_yield" not in e}
    assert len(without) == 1 and len(with_elements) == 1 and without != with_elements
    # a linear model keeps an element of its own stages (its state space is theirs)
    lin = _model(("force_feedback_filter", "valve_dynamics"))
    assert lin.linear and not lin.element.switchable


def test_a_users_stage_named_as_a_catalog_one_is_its_own_not_the_catalogs():
    """A user's force stage called coulomb_friction (twice the catalog's force) is the
    law the model steps; the catalog's stage of that name is left out of the flags, and
    a user's feedback stage leaves out the catalog's filter (one feedback stage)."""

    def doubled(F, v, p):
        return F - 2.0 * p.friction * np.tanh(v / p.v_eps)

    def passed(P, z, p):
        return P

    def no_rate(P, dP, z, p, dz):
        return

    mine = Stage("coulomb_friction", "force", doubled, ("friction", "v_eps"))
    fb = Stage("my_filter", "feedback", passed, ("k",), rate=no_rate)
    base = _model(("actuator_friction",))
    law = base._law.with_stages([*[(s, p) for s, p in base._law.stages
                                   if s.name != "coulomb_friction"],
                                 (mine, {"friction": 5e3, "v_eps": 1e-3}), (fb, {"k": 1.0})])
    stock = reduced.switchable(law)
    assert "coulomb_friction" not in {s.name for s in stock}
    assert "feedback" not in {s.kind for s in stock}
    comp = law.composition(reduced.KERNELS, switchable=stock)
    assert mine in comp.stages and fb in comp.stages
    assert law.vector(comp)[-len(stock):].tolist() == [0.0] * len(stock)
    with pytest.raises(VtableError, match="needs its parameters"):
        comp.vector(law.hydraulics, [None] * len(comp.stages))
    # stepped: the user's law, as the element of its own stages steps it, not the catalog's
    t, x = _command()
    m = base
    stepped = []
    for c in (comp, law.composition(reduced.KERNELS), m.element):
        sp = law.vector(c) if c is not m.element else m.sp
        stepped.append(simulate_reduced(c.module, x, t[1] - t[0], m.M.shape[0], m.Minv, m.K,
                                        m.C, m.c2, m.bF, m.ax, sp, m.T, m.Tp, m.g, m.kp, m.kv,
                                        m.Aw, m.Wq, m.Wv, m.Fw)[3])
    assert np.array_equal(stepped[0], stepped[1])
    # the catalog's friction (1 kip) differs from the user's doubled 5 kN by several kN
    assert np.max(np.abs(stepped[0] - stepped[2])) > 0.1 * 2.0 * 5e3
