"""The parts of a reduced model kept across builds (`vtable.models.reduced_parts`): a model
built from kept parts predicts exactly what one built afresh does, whatever parameter moved
(a specimen, a table value, the servo loop, an effect), and a specimen moved alone keeps
its table (the parts kept by table are then reused)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from vtable.models import reduced_parts
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.params import presets
from vtable.tables.eerc import virtual_table


def _emptied() -> None:
    for cache in (reduced_parts._TABLES, reduced_parts._MECHANICS, reduced_parts._SERVOS,
                  reduced_parts._PITCH, reduced_parts._LAWS, reduced_parts._VIEWS):
        cache.clear()


def _moves(ph: Physics) -> dict[str, Physics]:
    spec = ph.specimen
    return {"specimen": dataclasses.replace(ph, specimen=dataclasses.replace(
                spec, frequency=spec.frequency * 1.03)),
            "table": dataclasses.replace(ph, table={"platen_mass": 30_000.0}),
            "loop": dataclasses.replace(ph, open_loop=dataclasses.replace(
                ph.open_loop, f_o=ph.open_loop.f_o * 0.97)),
            "effect": dataclasses.replace(ph, effects={
                **ph.effects, "actuator_friction": {"friction": 2.5}})}


@pytest.mark.parametrize("move", ["specimen", "table", "loop", "effect"])
def test_a_model_of_kept_parts_predicts_what_one_built_afresh_does(move):
    vt = virtual_table()  # a diagnosis builds every model on its campaign's table
    ph = Physics(nominal_open_loop(vt), presets.specimen("sdof_frame"),
                 {"pitch_flexibility": {}, "actuator_friction": {"friction": 3.0}})
    t = np.arange(1200) / 200.0
    x_c = 0.01 * np.sin(2 * np.pi * 2.0 * t) + 0.004 * np.sin(2 * np.pi * 7.0 * t)
    _emptied()
    before = ReducedModel(ph, vt).simulate(t, x_c)  # the parts of `ph` kept
    moved = _moves(ph)[move]
    kept = ReducedModel(moved, vt).simulate(t, x_c)
    _emptied()
    fresh = ReducedModel(moved, vt).simulate(t, x_c)
    assert not np.array_equal(fresh["avg_hacc"], before["avg_hacc"])  # the move is seen
    assert set(kept) == set(fresh)
    for c in fresh:
        np.testing.assert_array_equal(kept[c], fresh[c], err_msg=c)
    if move == "table":  # the moved value reaches the model
        assert ReducedModel(moved, vt).vt.table.geometry.mass == 30_000.0


def test_a_specimen_moved_alone_keeps_the_table():
    vt = virtual_table()  # a diagnosis builds every model on its campaign's table
    ph = Physics(nominal_open_loop(vt), presets.specimen("sdof_frame"), {"pitch_flexibility": {}})
    _emptied()
    a = ReducedModel(ph, vt)
    b = ReducedModel(_moves(ph)["specimen"], vt)
    c = ReducedModel(_moves(ph)["table"], vt)
    assert b.vt is a.vt and b.assembly.servo is a.assembly.servo
    assert c.vt is not a.vt
    assert not np.array_equal(b.K, a.K)  # the specimen's stiffness moved
