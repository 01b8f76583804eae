"""Simulator behaviour: command checks, limits, divergence, run files, Rerun recording."""

from __future__ import annotations

import dataclasses
import re
import tomllib

import numpy as np
import pytest
from conftest import nonlinear_controllers

from vtable import units
from vtable.controllers import standard_controllers
from vtable.errors import VtableError
from vtable.ident import transfer_function
from vtable.mjcf import build
from vtable.params import RigidBlock, SDOFSpecimen, presets
from vtable.runs import FORMAT_UNITS as CHANNEL_UNITS
from vtable.signals import band_limited_random, make_command, sine
from vtable.sim import SimulationDivergedError, Simulator
from vtable.sim.experiment import run_experiment
from vtable.viz.rerun_scene import log_run, read_rrd

IN = units.to_si(1.0, "in")


def test_command_beyond_stroke_or_velocity_is_refused(vt):
    sim = Simulator(build(vt))
    t = np.arange(0, 2, 0.001)
    with pytest.raises(VtableError, match=r"x command reaches 6.00 in .* stroke \(Table 2.2\)"):
        sim.run(t, {"x": 6 * IN * np.sin(np.pi * t / 2)})
    with pytest.raises(VtableError, match=r"velocity reaches .* in/s .*velocity limit"):
        sim.run(t, {"x": 1 * IN * np.sin(2 * np.pi * 5 * t)})  # 31 in/s
    with pytest.raises(VtableError, match="unknown command DOF 'y'"):
        sim.run(t, {"y": 0 * t})


@pytest.mark.parametrize("spec, msg", [
    (SDOFSpecimen(weight=units.to_si(60, "kip"), height=units.to_si(520, "in"), frequency=2.0,
                  damping=0.02), "above the 40 ft overhead clearance"),
    (RigidBlock(weight=units.to_si(150, "kip"), height=units.to_si(40, "in")),
     "above the table's capacity of 130 kips"),
])
def test_specimen_beyond_table_limits(vt, spec, msg):
    with pytest.raises(VtableError, match=msg):
        build(vt, spec)


def test_force_exceedance_is_reported_not_clipped(vt):
    sim = Simulator(build(vt, presets.specimen("concrete_blocks")))
    t, x = sine(2.0, 0.001, 8.0, 0.4 * IN, ramp=0.5)  # 20 in/s, 2.6 g on 170 kips
    res = sim.run(t, {"x": x})
    over = [e for e in res.exceedances if e.quantity == "force" and e.actuator.startswith("H")]
    assert over and over[0].peak > over[0].limit
    i = res.built.force_actuators.index(over[0].actuator)
    assert np.max(np.abs(res.forces[:, i])) > over[0].limit  # the force was not clipped
    assert "exceeds 50 kip from t =" in str(over[0])


def test_divergence_stops_with_time_and_cause(vt, tmp_path):
    hot = dataclasses.replace(vt, horizontal_servo=dataclasses.replace(
        vt.horizontal_servo, k_t=vt.horizontal_servo.k_t * 40, k_p=0.0))
    cmd = make_command("sine", duration=5.0, frequency=1.0, peak_in=0.05)
    with pytest.raises(SimulationDivergedError, match=r"diverged at t = \d+\.\d+ s") as e:
        run_experiment(presets.specimen("none"), cmd, vt=hot, out=tmp_path / "run")
    assert "nothing written" in str(e.value)
    assert not any(tmp_path.iterdir())


def test_run_files_follow_the_format(vt, tmp_path):
    cmd = make_command("random", duration=3.0, peak_in=0.2, seed=4)
    exp = run_experiment(presets.specimen("sdof_frame"), cmd, out=tmp_path / "r1")
    meta = tomllib.loads((tmp_path / "r1.toml").read_text())
    assert meta["format"] == "vtable-run/1"
    assert meta["specimen"] == {"kind": "sdof", "weight_kip": pytest.approx(68.4),
                                "height_in": pytest.approx(219.0), "frequency_hz": 2.87,
                                "damping": 0.01}
    assert meta["control"]["horizontal"] == {"gain": 9.0, "delta_p": 1.5, "rate": 5.0}
    assert meta["command"]["kind"] == "random"
    header = (tmp_path / "r1.csv").read_text().splitlines()[0].split(",")
    assert header[0] == "time"
    known = [h for h in header[1:] if h in CHANNEL_UNITS]
    extra = [h for h in header[1:] if h not in CHANNEL_UNITS]
    assert set(CHANNEL_UNITS) <= set(known)  # every Table 2.3 channel for this specimen
    assert set(extra) == set(meta["units"])  # the full state, with declared units
    data = np.loadtxt(tmp_path / "r1.csv", delimiter=",", skiprows=1)
    col = {h: data[:, i] for i, h in enumerate(header)}
    np.testing.assert_allclose(col["h_span"], exp.result.commands[:, 0] / IN, rtol=1e-9,
                               atol=1e-12)
    assert np.max(np.abs(col["h_span"])) == pytest.approx(0.2, rel=1e-3)  # 200 Hz samples
    # signs: avg_hdisp follows the command at low frequency; + force pushes the table +x
    tf = transfer_function(col["h_span"], col["avg_hdisp"], 200.0, nperseg=256)
    assert abs(tf.at(1.0)) == pytest.approx(1.0, abs=0.05) and tf.at(1.0).real > 0.8
    push = col["h1_force"] + col["h2_force"] + col["h3_force"]
    assert np.corrcoef(push, col["avg_hacc"])[0, 1] > 0.5
    np.testing.assert_allclose(np.diff(col["time"]), 0.005, rtol=1e-6)
    # absolute top-mass displacement = table + pitch·h + relative (small angles)
    pot = col["pot_n_sw"]
    recon = (col["state_q_x"] + 5.5626 * col["state_q_pitch"] + col["state_q_x_s"]) / IN
    assert np.max(np.abs(pot - recon)) < 0.01 * np.max(np.abs(pot))


def test_rerun_recording_reads_back(vt, tmp_path):
    cmd = make_command("sine", duration=2.0, frequency=2.0, peak_in=0.1)
    exp = run_experiment(presets.specimen("sdof_frame"), cmd)
    log_run(exp.run, tmp_path / "s.rrd", exaggeration=100.0)
    d = read_rrd(tmp_path / "s.rrd")
    for ent in ("/world/table/slab", "/world/table/slab/mesh", "/world/table/slab/frame",
                "/world/table/slab/top_mass", "/world/actuators/H1/line",
                "/world/actuators/V3/force", "/world/actuators/P2/line", "/channels/avg_hdisp",
                "/channels/pitch_acc", "/channels/p1_stab"):
        assert ent in d, ent
    rb = d["/channels/avg_hdisp"][0]
    values = np.array([v[0] for v in rb.column("Scalars:scalars").to_pylist()])
    np.testing.assert_allclose(values, exp.channel("avg_hdisp"), rtol=1e-12)
    # the slab's quaternion carries the exaggerated pitch
    tr = d["/world/table/slab"][0]
    quats = np.array(tr.column("Transform3D:quaternion").to_pylist())[:, 0, :]
    pitch = 2 * np.arcsin(np.clip(quats[:, 1], -1, 1))  # small roll/twist
    np.testing.assert_allclose(pitch, 100.0 * exp.result.joint("pitch"), atol=1e-6)
    # one quantity per view, its unit in its name: θ (rad) and θ̈ (rad/s²) apart (issue 19:
    # on one axis the pitch looked flat)
    from vtable.viz.diagnosis_rerun import read_blueprint_views

    views = {v["name"]: v for v in read_blueprint_views(tmp_path / "s.rrd")
             if v.get("class") == "TimeSeries"}
    assert {"pitch (rad)", "pitch acceleration (rad/s²)", "table motion (in)",
            "forces (kip)"} <= set(views), sorted(views)
    assert all(re.search(r"\((in|rad|rad/s²|kip|g)\)$", n) for n in views), sorted(views)


def test_nonlinear_valve_matches_linear_small_and_loses_gain_large(vt):
    b = build(vt)
    res = {}
    for amp in (0.003, 0.1):
        t, x = band_limited_random(12.0, 0.001, (0, 20), rms=amp * IN, seed=3)
        for name, ctl in (("lin", standard_controllers(vt)), ("nl", nonlinear_controllers(vt))):
            r = Simulator(b, ctl).run(t, {"x": x}, check=False)
            tf = transfer_function(r.commands[:, 0], r.joint("x"), 200, nperseg=512)
            res[amp, name] = np.abs(tf.at([2.0, 5.0, 10.0]))
    np.testing.assert_allclose(res[0.003, "nl"], res[0.003, "lin"], rtol=0.01)
    # appendix C: the flow gain falls with load, so at large amplitude x_t/x_c drops
    assert res[0.1, "nl"][2] < 0.9 * res[0.1, "lin"][2]


def test_nonlinear_valve_caps_velocity_at_rated_flow(vt):
    b = build(vt)
    t, x = sine(3.0, 0.001, 4.0, 1.5 * IN, ramp=0.5)  # asks for 38 in/s
    r = Simulator(b, nonlinear_controllers(vt)).run(t, {"x": x}, check=False)
    v_max = np.max(np.abs(r.joint("x", "qvel")))
    rated = vt.actuator("H1").flow / vt.actuator("H1").area  # 25.8 in/s (§2.2: 25 in/s)
    assert v_max < 1.02 * rated
    assert v_max > 0.8 * rated
