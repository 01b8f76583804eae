"""The sensor consistency check (vtable.diagnose.sensors): a run's table acceleration
against its displacement's second derivative. On the independent truth simulator's runs
the two agree; the same run with its accelerometer put behind a mount resonance and a
low-pass (applied here with scipy.signal, a known truth) is flagged and the mount's
parameters are recovered; LNEC's measured run is flagged (its disagreement measured
independently by H1: |ẍ/s²x| 1.5 near 10 Hz, about 2.4 near 15 Hz, phase through 180° at
15-18 Hz)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import real_data

from vtable.diagnose.campaign import Campaign
from vtable.diagnose.sensors import sensor_check
from vtable.runs import read_run


@pytest.fixture(scope="module")
def truth_run(tmp_path_factory):
    import truth
    from truth import controllers as tc
    folder = tmp_path_factory.mktemp("sensors")
    table = truth.lnec_table(controller=tc.pid(129.93, p=1.0, i=0.5))
    cmd = truth.random_command(30.0, (0.0, 40.0), rms_in=0.06, seed=3, pink=True)
    res = truth.simulate(table, truth.none(), cmd, fs=200.0)
    path = truth.write_run(folder / "pink", res, declared=truth.none(), noise=0.01, seed=4)[0]
    return read_run(path)


def mounted(acc: np.ndarray, fs: float, f_m: float, z_m: float, f_c: float) -> np.ndarray:
    """The accelerometer behind a mount (ω_m, ζ_m) and a 2nd-order Butterworth low-pass,
    applied exactly in the frequency domain (the truth the check must recover)."""
    n = 1 << math.ceil(math.log2(2 * len(acc)))
    s = 2j * math.pi * np.fft.rfftfreq(n, 1 / fs)
    wm, wc = 2 * math.pi * f_m, 2 * math.pi * f_c
    G = wm**2 / (s**2 + 2 * z_m * wm * s + wm**2) * wc**2 / (s**2 + math.sqrt(2) * wc * s
                                                             + wc**2)
    return np.fft.irfft(np.fft.rfft(acc, n) * G, n)[: len(acc)]


def test_a_rigid_platen_agrees(truth_run):
    c = sensor_check(truth_run)
    assert c is not None and c.agree and c.mount is None
    assert len(c.bands) >= 3
    for _, m, ph, _ in c.bands:
        assert abs(m - 1) < 0.03 and abs(ph) < 3.0
    assert Campaign.of([truth_run]).sensors == []


def test_an_accelerometer_on_a_mount_is_flagged_and_its_mount_fitted(truth_run):
    run = truth_run
    saved = run.channels["avg_hacc"]
    try:
        run.channels["avg_hacc"] = mounted(saved, run.fs, 14.0, 0.06, 35.0)
        c = sensor_check(run)
    finally:
        run.channels["avg_hacc"] = saved
    assert c is not None and not c.agree
    f_m, z_m, f_c = c.mount
    assert f_m == pytest.approx(14.0, rel=0.02)
    assert z_m == pytest.approx(0.06, rel=0.3)
    assert f_c == pytest.approx(35.0, rel=0.15)
    assert c.misfit < 0.05
    assert "14.0 Hz" in c.text() and "no effect on the platen" in c.text()


@real_data.NEEDED
def test_lnecs_measured_run_is_flagged(tmp_path):
    run = read_run(real_data.copy_run(tmp_path))
    c = sensor_check(run)
    assert c is not None and not c.agree
    ratio = {b: m for b, m, _, _ in c.bands}
    assert 1.4 < ratio["10-20 Hz"] < 2.0 and 1.1 < ratio["5-10 Hz"] < 1.4
    f_m, z_m, f_c = c.mount
    assert 15.0 < f_m < 19.0 and z_m < 0.3 and 20.0 < f_c < 45.0
    assert c.text() in Campaign.of([run]).notes


def test_the_mount_fits_jacobian_is_its_laws_derivative():
    """`mount_log_derivatives` (the sensor check's Jacobian) against central differences
    of ln `mount_response`: a wrong sign or factor of 2π in any column is off by ≥ 50 %."""
    from vtable.effects.sensor import mount_log_derivatives, mount_response
    w = 2 * math.pi * np.linspace(0.5, 80.0, 400)
    p = np.array([14.0, 0.06, 35.0])
    J = mount_log_derivatives(w, *p)
    for i in range(3):
        h = np.zeros(3)
        h[i] = 1e-6 * p[i]
        fd = (np.log(mount_response(w, *(p + h))) - np.log(mount_response(w, *(p - h))))
        fd /= 2 * h[i]
        assert np.max(np.abs(J[:, i] - fd)) < 1e-6 * np.max(np.abs(fd))
