"""Controllers as objects (issue 18): the declared digital controller (PID with a filtered
derivative and feedforward, TVC with a reference generator and acceleration feedback,
notches, ΔP stabilisation) in the reduced model and the virtual table, against the
closed loop x_t/x_c derived by hand in tests/models/test_truth_controllers.py (not vtable's
code), and the truth simulator's runs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from truth.closed_loop import closed_loop, lnec_constants

from vtable.models.physics import Physics
from vtable.models.reduced import ReducedModel
from vtable.params.specimen import NoSpecimen
from vtable.runs.lab import lab_table
from vtable.runs.table import table_from_dict
from vtable.tables.lab import bare_loop

F = np.array([0.3, 1.0, 3.0, 6.0, 10.0, 15.0, 22.0, 30.0])
KD = 129.93

CASES = {
    "pid_ff": ({"p": 1.2, "i_per_s": 0.8, "d_s": 0.004, "derivative_filter_s": 0.002,
                "feedforward_velocity_s": 0.012, "feedforward_acceleration_s2": 2e-4},
               dict(p=1.2, i=0.8, d=0.004, tau_f=0.002, Tv=0.012, Ta=2e-4)),
    "pid_dp": ({"p": 1.0, "i_per_s": 0.5, "pressure_gain_v_per_pa": 2e-7,
                "velocity_gain_v_s_per_m": 2.0},
               dict(p=1.0, i=0.5, kdp=2e-7, kv=2.0)),
    "tvc": ({"p": 1.0, "velocity_gain_v_s_per_m": 3.0, "acceleration_gain_v_s2_per_m": 0.01,
             "feedforward_velocity_s": 0.01, "feedforward_acceleration_s2": 1e-4,
             "reference_frequency_hz": 40.0, "reference_damping": 0.8},
            dict(kv=3.0, ka=0.01, Tv=0.01, Ta=1e-4, ref=(40.0, 0.8))),
    "notches": ({"p": 1.0, "notch": [{"frequency_hz": 8.0, "width_hz": 3.0, "depth_db": 30.0,
                                      "on": "error"},
                                     {"frequency_hz": 20.0, "width_hz": 6.0, "depth_db": 20.0,
                                      "on": "drive"}]},
                dict(notches=((8.0, 3.0, 30.0, "error"), (20.0, 6.0, 20.0, "drive")))),
}


def _notch(s, f, w, depth):
    wn, zp = 2 * math.pi * f, w / (2 * f)
    zz = zp * 10 ** (-depth / 20)
    return (s**2 + 2 * zz * wn * s + wn**2) / (s**2 + 2 * zp * wn * s + wn**2)


def hand(case: str, f: np.ndarray) -> np.ndarray:
    """x_t/x_c by the hand-derived closed loop (the truth's tests)."""
    s = 2j * math.pi * f
    kw = dict(CASES[case][1])
    Ne = Nd = R = 1.0
    for fn, w, depth, on in kw.pop("notches", ()):
        if on == "error":
            Ne = Ne * _notch(s, fn, w, depth)
        else:
            Nd = Nd * _notch(s, fn, w, depth)
    if "ref" in kw:
        fg, zg = kw.pop("ref")
        wg = 2 * math.pi * fg
        R = wg**2 / (s**2 + 2 * zg * wg * s + wg**2)
    return closed_loop(s, **lnec_constants(), **kw, Ne=Ne, Nd=Nd, R=R)


def lab(case: str):
    ctl = {"kind": "tvc" if case == "tvc" else "pid", "displacement_gain_v_per_m": KD,
           **CASES[case][0]}
    return lab_table(table_from_dict({"preset": "lnec-st1d", "controller": ctl}))


def reduced_response(case: str, f: np.ndarray) -> np.ndarray:
    """x_t/x_c of vtable's reduced model: its exact linear system's frequency response."""
    t = lab(case)
    m = ReducedModel(Physics(bare_loop(t), NoSpecimen()), t)
    A, B = m._linear[0], m._linear[1]
    nq = m.M.shape[0]
    c = np.zeros(A.shape[0])
    c[:nq] = m.ax
    return np.array([c @ np.linalg.solve(2j * math.pi * fk * np.eye(len(A)) - A, B)
                     for fk in f])


@pytest.mark.parametrize("case", list(CASES))
def test_reduced_model_closed_loop_is_the_hand_derivation(case):
    """The reduced model's x_t/x_c within 1 % (magnitude) and 1.5° of the hand-derived
    closed loop up to 30 Hz (vtable reads a command's derivatives and the platen's
    acceleration through 0.5 ms filters: 5° at 30 Hz on those terms alone)."""
    h, v = hand(case, F), reduced_response(case, F)
    err = np.abs(v / h - 1)
    phase = np.degrees(np.abs(np.angle(v / h)))
    assert err.max() < 0.01 and phase.max() < 1.5, (err.round(4), phase.round(2))


# ---------------------------------------------------------------------------------------
# identify on the truth simulator's runs: the declared controller's structure fitted

FS = 200.0


def _truth_run(folder, controller, seed: int):
    import truth
    from truth import controllers as tc
    kw = {k: v for k, v in controller.items() if k != "kind"}
    law = getattr(tc, controller["kind"])(KD, **kw)
    table = truth.lnec_table(controller=law)
    cmd = truth.random_command(40.0, (0.0, 40.0), rms_in=0.08, seed=seed, pink=True)
    res = truth.simulate(table, truth.none(), cmd, fs=FS)
    return truth.write_run(folder / controller["kind"], res, declared=truth.none(),
                           noise=0.01, seed=seed)[0]


@pytest.mark.parametrize("controller", [
    {"kind": "pid", "p": 1.0, "i": 1.5, "feedforward_velocity": 0.02,
     "feedforward_acceleration": 1e-4},
    {"kind": "tvc", "p": 1.0, "velocity_gain": 2.0, "acceleration_gain": 0.005,
     "feedforward_velocity": 0.015, "reference": (35.0, 0.7)},
])
def test_identify_fits_the_declared_controllers_loop(tmp_path, capsys, controller):
    """identify on a PID+feedforward and a TVC table (the truth simulator, 1 % noise): the
    declared controller's structure is the best, and its loop is the table's design
    (eq 6.16 of the LNEC constants with the declared velocity gain) within 3 %."""
    import json

    from vtable.cli import main
    from vtable.runs import read_run
    from vtable.runs.lab import run_table
    path = _truth_run(tmp_path, controller, seed=5)
    code = main(["identify", str(path), "--json", str(tmp_path / "id.json")])
    err = capsys.readouterr().err
    assert code == 0, err
    d = json.loads((tmp_path / "id.json").read_text())["runs"][0]
    ls = d["loop_structure"]
    assert ls["fits_eq_6_15"] and ls["best"] == "declared", ls["why"]
    ref = bare_loop(run_table(read_run(path)))  # eq 6.16 of the declared table
    p = d["open_loop"]["params"]
    assert p["f_o"] == pytest.approx(ref.f_o, rel=0.03)
    assert p["xi_o"] == pytest.approx(ref.xi_o, rel=0.03)
    assert p["k_o"] == pytest.approx(ref.k_o, rel=0.03)
    assert p["tau"] == pytest.approx(0.0246, rel=0.05)


# ---------------------------------------------------------------------------------------
# the virtual table (MuJoCo, the controller fused as a linear controller) and the reduced
# model: the controller adds no disagreement beyond the bare P loop's

def _virtual_vs_reduced(t) -> dict[str, float]:
    """NRMS difference of the reduced model's prediction from the virtual table's run
    (random 0-40 Hz, 10 s, 200 Hz) on x_t and ẍ_t."""
    from vtable.signals import Command, band_limited_random
    from vtable.sim import simulate, standard_physics

    vt = t
    tt, x = band_limited_random(10.0, 0.001, (0, 40), rms=0.0003, seed=3)
    cmd = Command("random 0-40 Hz", tt, x, {"kind": "random", "band_hz": [0.0, 40.0]})
    run = simulate(standard_physics(NoSpecimen(), vt=vt), cmd, 200.0, vt=vt)
    p = ReducedModel(standard_physics(NoSpecimen(), vt=vt), vt).predict(run)
    return {ch: float(np.sqrt(np.mean((run.channel(ch) - p[ch]) ** 2) /
                          np.mean(run.channel(ch) ** 2))) for ch in ("avg_hdisp", "avg_hacc")}


@pytest.mark.parametrize("case", list(CASES))
def test_virtual_table_agrees_with_the_reduced_model_under_each_controller(case):
    """Each controller in both models: the NRMS difference (1.3 % on ẍ_t, 0.3 % on x_t
    with the P loop alone: the multibody's own) grows by no more than 0.3 points."""
    bare = _virtual_vs_reduced(lab_table(table_from_dict({"preset": "lnec-st1d"})))
    with_ctl = _virtual_vs_reduced(lab(case))
    for ch in bare:
        assert with_ctl[ch] < bare[ch] + 0.003 and with_ctl[ch] < 0.02, (ch, with_ctl, bare)


def test_a_digital_controller_on_the_eerc_6_dof_table():
    """PID + feedforward + ΔP stabilisation on Berkeley's table: the control stage drives
    H1-H3's x DOF (twist keeps the P law) in the multibody table, and the reduced model's
    lumped x loop. On x_t they agree better than under the report's analog loop; on ẍ_t
    the velocity feedforward (on a valve without lag) opens a gap the LNEC table does not
    show: 2.4 % against the analog loop's 1.0 % (measured; its cause is not yet found —
    neither the command's interpolation nor the step, which the integral term alone also
    tightens without a gap). Bounded here so that a change is seen."""
    kd = 2.0 / 0.0254
    ctl = {"kind": "pid", "displacement_gain_v_per_m": kd, "p": 1.0, "i_per_s": 1.0,
           "feedforward_velocity_s": 0.02, "pressure_gain_v_per_pa": 1.5e-8}
    # the valve flow gain K_q = k_t/k_d of Table B.5's loop, as a lab would declare it
    t = lab_table(table_from_dict({"preset": "eerc", "controller": ctl, "horizontal": {
        "valve_flow_gain_m3_per_s_v": 0.005432311716}}))
    assert t.control is not None and not t.uniaxial
    got, bare = _virtual_vs_reduced(t), _virtual_vs_reduced(lab_table(None))
    assert got["avg_hdisp"] < bare["avg_hdisp"] + 0.003, (got, bare)
    assert got["avg_hacc"] < 0.03, (got, bare)
