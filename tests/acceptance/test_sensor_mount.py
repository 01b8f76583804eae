"""sensor_mount (issue 32, deliverable 2): the table accelerometer on a mount behind its
conditioner's low-pass. Its law is the one `diagnose.sensors` fits to a run's ẍ/s²x; the
virtual table and the reduced model apply it to the table acceleration alone; and a
diagnosis of a campaign the independent truth simulator (tests/truth: its own mount, poles
discretised by a first-order hold, no vtable code) makes with a mount hidden and the
declaration perturbed finds it with the catalog, its resonance within 10 %."""

import functools

import numpy as np
import pytest
import truth
from conftest import truth_runs

from vtable.diagnose.engine import Diagnoser
from vtable.diagnose.sensors import mount_ratio
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.params import presets
from vtable.signals import make_command
from vtable.sim import simulate

MOUNT = {"f_m": 17.0, "zeta_m": 0.09, "f_c": 30.0}  # LNEC's run, as sensors.py fits it


def test_the_law_is_the_mount_ratio_and_only_the_acceleration_sees_it():
    f = np.array([0.0, 5.0, 17.0, 30.0])
    R = mount_ratio(f, 17.0, 0.09, 30.0)
    assert R[0] == pytest.approx(1.0)
    # at f_m the mount alone is 1/(2 j ζ): |R| = 1/(2 ζ) times the low-pass there
    s = 2j * np.pi * 17.0
    wc = 2 * np.pi * 30.0
    assert abs(R[2]) == pytest.approx(abs(1 / (2j * 0.09) * wc**2 / (s**2 + np.sqrt(2) * wc * s
                                                                       + wc**2)), rel=1e-9)
    cmd = make_command("random", duration=11.0, band=(0.0, 25.0), peak_in=0.15, seed=2)
    base = Physics(nominal_open_loop(), presets.specimen("sdof_frame"), {})
    with_mount = Physics(base.open_loop, base.specimen, {"sensor_mount": MOUNT})
    r0, r1 = simulate(base, cmd, name="rigid"), simulate(with_mount, cmd, name="mount")
    for c in r0.channels:
        if c != "avg_hacc":
            np.testing.assert_array_equal(r0.channel(c), r1.channel(c))
    a0, a1 = r0.channel("avg_hacc"), r1.channel("avg_hacc")
    assert np.linalg.norm(a1 - a0) > 0.5 * np.linalg.norm(a0)
    # the reduced model applies the same law: it agrees with the virtual table as it does
    # without the mount (its resolution, 0.3-0.6 %)
    out = ReducedModel(with_mount).simulate(r1.time, r1.channel("h_span"))
    assert np.linalg.norm(out["avg_hacc"] - a1) / np.linalg.norm(a1) < 0.01


@functools.cache
def _mount_campaign(tmp: str):
    spec = truth.sdof(68.0, 219.0, 2.87, 0.02)
    decl = truth.perturb(spec, seed=7, frequency=0.03, damping=1.5, weight=0.05)
    table = truth.eerc_table(effects={"sensor_mount": dict(MOUNT)})
    cmds = [("random_0", truth.random_command(12.0, (0, 25), peak_in=0.1, seed=1)),
            ("random_1", truth.random_command(12.0, (0, 25), peak_in=0.3, seed=2)),
            ("earthquake", truth.earthquake_command("elcentro", peak_in=2.0))]
    runs = truth_runs(tmp, table, spec, decl, cmds, noise=0.01, seed=30)
    return Diagnoser(runs).diagnose()


def test_a_hidden_mount_is_found_with_the_catalog(tmp_path_factory):
    d = _mount_campaign(str(tmp_path_factory.mktemp("mount")))
    assert d.final_effects == ["sensor_mount"], d.headline
    p = d.final.effects["sensor_mount"]
    assert p["f_m"] == pytest.approx(MOUNT["f_m"], rel=0.1)
    assert d.final_error < 2 * d.noise_floor
    assert d.start_error > 3 * d.final_error
    assert len(d.headline) <= 200 and d.headline.startswith("added sensor_mount: ")


def test_not_tried_where_the_table_channels_agree():
    """Runs whose table acceleration is the second derivative of their displacement show no
    mount: the diagnosis skips it, saying why (the virtual table's pitch campaign)."""
    from conftest import effect_diagnosis

    _, diag, d = effect_diagnosis(("pitch_flexibility",))
    assert not diag.campaign.sensors
    for r in d.rounds:
        assert "the runs show no mount" in r.skipped["sensor_mount"]
    assert "sensor_mount" not in [c.effect for r in d.rounds for c in r.ranking]
