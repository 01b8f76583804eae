"""[table.horizontal] force_measured: what the actuators' force channels measure, the net
force the rod transmits to the platen ("load_cell", the default) or A·ΔP ("delta_p"), read
by the reduced model and the virtual table alike."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest
from conftest import campaign_commands

from vtable.errors import VtableError
from vtable.hydraulics.element import PISTON_AREA
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.params import presets
from vtable.runs.lab import lab_table
from vtable.runs.table import table_from_dict
from vtable.sim import simulate
from vtable.tables.eerc import virtual_table
from vtable.units import KIP

FRICTION_KIP = 3.0  # total over the three horizontal actuators


@functools.cache
def _physics():
    return Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                   {"actuator_friction": {"friction": FRICTION_KIP}})


@functools.cache
def _runs():
    """The virtual table's random run (0-25 Hz, 0.05 in) with friction, its force channels
    read as a load cell and as A·ΔP."""
    ph, random = _physics(), campaign_commands()[0]
    return (simulate(ph, random),
            simulate(ph, random, vt=dataclasses.replace(virtual_table(),
                                                        force_measured="delta_p")))


def test_the_key_is_read_carried_and_refused_when_unknown():
    for fm in ("load_cell", "delta_p"):
        desc = table_from_dict({"preset": "eerc", "horizontal": {"force_measured": fm}})
        assert desc.horizontal.force_measured == fm
        assert lab_table(desc).force_measured == fm
    assert lab_table(None).force_measured == "load_cell"  # undeclared: today's channels
    assert virtual_table().force_measured == "load_cell"
    with pytest.raises(VtableError, match=r"\[table\.horizontal\]\.force_measured: expected "
                       r"one of 'load_cell', 'delta_p', got 'strain_gauge'"):
        table_from_dict({"preset": "eerc", "horizontal": {"force_measured": "strain_gauge"}})


def test_reduced_model_force_is_a_dp_or_the_net_force():
    ph = _physics()
    run = _runs()[0]
    t, xc = run.time, run.channel("h_span")
    dp = ReducedModel(ph, dataclasses.replace(virtual_table(), force_measured="delta_p"))
    lc = ReducedModel(ph)
    assert not dp.linear  # the friction stage: the RK4 path
    hist = dp.histories(t, xc)
    up, P = hist.up, hist.p_l
    na = len(dp.vt.group("horizontal"))
    a_dp = dp.sp[PISTON_AREA] * P[::up] / na  # one actuator's A·P_L
    f_dp, f_lc = dp.simulate(t, xc), lc.simulate(t, xc)
    # a typed prediction: the channels by name on the run's grid, the step it was
    # integrated at, and through pickle (a Dask worker's result) unchanged
    import pickle

    assert np.array_equal(f_dp.t, t) and f_dp.h == pytest.approx((t[1] - t[0]) / up)
    assert hist.h == f_dp.h and len(f_dp["h1_force"]) == len(t)
    back = pickle.loads(pickle.dumps(f_dp))
    assert back.h == f_dp.h and np.array_equal(back["h1_force"], f_dp["h1_force"])
    assert np.max(np.abs(f_dp["h1_force"] - a_dp)) <= 1e-9 * np.max(np.abs(a_dp))
    for ch in ("h2_force", "h3_force"):
        assert np.array_equal(f_dp[ch], f_dp["h1_force"])
    # the same motion; the load cell reads A·ΔP less each actuator's friction F_r sign(ẋ)
    assert np.array_equal(f_dp["avg_hdisp"], f_lc["avg_hdisp"])
    v = f_lc["h_vel"]
    moving = np.abs(v) > 0.2 * np.max(np.abs(v))
    diff = (f_dp["h1_force"] - f_lc["h1_force"])[moving] * np.sign(v[moving])
    assert np.median(diff) == pytest.approx(FRICTION_KIP * KIP / 3, rel=0.02)
    assert np.std(diff) < 0.02 * FRICTION_KIP * KIP / 3


def test_virtual_table_force_is_a_dp_or_the_net_force():
    ph = _physics()
    lc, dp = _runs()
    assert np.array_equal(dp.channel("avg_hdisp"), lc.channel("avg_hdisp"))
    v = lc.channel("h_vel")
    moving = np.abs(v) > 0.2 * np.max(np.abs(v))
    for a in ("h1", "h2", "h3"):
        diff = (dp.channel(f"{a}_force") - lc.channel(f"{a}_force"))[moving] * np.sign(v[moving])
        assert np.median(diff) == pytest.approx(FRICTION_KIP * KIP / 3, rel=0.02)
    # the reduced model reads the same channel
    pred = ReducedModel(ph, dataclasses.replace(virtual_table(), force_measured="delta_p")
                        ).predict(dp)
    y = dp.channel("h1_force")
    assert np.sqrt(np.mean((pred["h1_force"] - y) ** 2) / np.mean(y**2)) < 0.02


def test_a_model_holds_a_reading_of_its_own_and_runs_made_say_theirs():
    """`Physics.force_measured` (what a diagnosis found, `vtable.diagnose.reading`) reads
    the force channels as a table declaring it does; runs the virtual table makes declare
    what their force channels measured."""
    ph = _physics()
    lc, dp = _runs()
    t, xc = dp.time, dp.channel("h_span")
    on_table = ReducedModel(ph, dataclasses.replace(virtual_table(), force_measured="delta_p"))
    held = ReducedModel(dataclasses.replace(ph, force_measured="delta_p"))
    a, b = on_table.simulate(t, xc), held.simulate(t, xc)
    for ch in ("h1_force", "avg_hdisp", "avg_hacc"):
        assert np.array_equal(a[ch], b[ch]), ch
    assert not np.allclose(b["h1_force"], ReducedModel(ph).simulate(t, xc)["h1_force"])
    assert held.vt.force_measured == "delta_p" and ph.on_table(virtual_table()) \
        .force_measured == "load_cell"
    assert lc.meta["table"]["horizontal"]["force_measured"] == "load_cell"
    assert dp.meta["table"]["horizontal"]["force_measured"] == "delta_p"
    # read back, the declaration is the table's
    assert lab_table(table_from_dict(dp.meta["table"])).force_measured == "delta_p"
