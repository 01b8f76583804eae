"""What the data allow (issue 32, deliverable 1) and the verdict a lab engineer reads
(deliverable 4): the black-box reference against an independent few-line H1 -> FIR
predictor, the bound and the error's split on truths with and without a missing
nonlinearity, the headline's length and the findings' keys."""

import json

import numpy as np
import pytest
import scipy.signal
from conftest import effect_campaign, effect_diagnosis

from vtable.diagnose.findings import HEADLINE_MAX, headline
from vtable.diagnose.limits import black_box
from vtable.diagnose.model import TableModel
from vtable.diagnose.result import ModelComparison


def _independent_reference(x, y, n_train, n):
    """H1 from Hann-windowed, half-overlapping, mean-removed frames (numpy FFTs), its
    inverse FFT centred as a FIR, played on the whole command: held-out NRMS."""
    w = np.hanning(n + 1)[:-1]  # periodic Hann, as scipy's default
    sxy = np.zeros(n // 2 + 1, complex)
    sxx = np.zeros(n // 2 + 1)
    for k in range(0, n_train - n + 1, n // 2):
        X = np.fft.rfft(w * (x[k:k + n] - x[k:k + n].mean()))
        Y = np.fft.rfft(w * (y[k:k + n] - y[k:k + n].mean()))
        sxy += np.conj(X) * Y
        sxx += np.abs(X) ** 2
    h = np.fft.irfft(np.where(sxx > 1e-6 * sxx.max(), sxy / np.maximum(sxx, 1e-300), 0), n)
    y_hat = np.convolve(x, np.roll(h, n // 2))[n // 2:n // 2 + len(x)]
    held = slice(n_train, len(x))
    return np.linalg.norm(y_hat[held] - y[held]) / np.linalg.norm(y[held])


def test_black_box_matches_an_independent_h1_fir():
    rng = np.random.default_rng(3)
    fs, n_all = 200.0, 12000
    x = scipy.signal.lfilter(*scipy.signal.butter(4, 20.0, fs=fs), rng.standard_normal(n_all))
    b, a = scipy.signal.iirpeak(6.0, 8.0, fs=fs)  # a resonance at 6 Hz
    y = scipy.signal.lfilter(b, a, x) + 0.3 * x
    y_noisy = y + 0.01 * np.std(y) * rng.standard_normal(n_all)
    n_train = 7200
    err, frame, _ = black_box(x, y_noisy, slice(0, n_train), slice(n_train, n_all))
    indep = min(_independent_reference(x, y_noisy, n_train, n) for n in (256, 512, 1024))
    assert err == pytest.approx(indep, rel=0.02)
    assert frame in (256, 512, 1024)
    # a time-invariant truth with 1 % noise: the black box comes within a few % (its
    # frames' leakage and the FIR's length)
    assert 0.009 < err < 0.08
    # nothing to train on: no reference
    assert black_box(x, y, slice(0, 300), slice(300, 600)) is None


def test_limits_on_a_linear_truth_the_bound_is_the_noise():
    """Pitch flexibility hidden and found: the final model's held-out residual is the
    sensor noise, so the bound is the noise and nothing is beyond; the physics model beats
    the black box, and the JSON, the headline and the findings say so."""
    _, _, d = effect_diagnosis(("pitch_flexibility",))
    lim = d.limits
    assert lim.noise == pytest.approx(d.noise_floor, rel=0.05)
    assert lim.noise <= lim.bound < 1.25 * lim.noise
    assert lim.beyond < 0.3 * lim.noise
    assert lim.reference > 3 * d.final_error  # short runs, a 1 %-damped specimen
    for g in lim.groups:  # e² ≈ within² + incoherent² on every group
        inc = g.bound if g.resolved else None
        if inc is not None and g.bound > g.noise:
            assert g.error ** 2 == pytest.approx(g.within_reach ** 2 + inc ** 2, rel=0.2)
    j = json.loads(json.dumps(d.to_json()))
    assert j["bound"] == pytest.approx(lim.bound) and j["reference"] == pytest.approx(
        lim.reference)
    assert len(j["limits"]["groups"]) == len(lim.groups) > 0
    assert len(j["headline"]) <= HEADLINE_MAX
    assert j["headline"].startswith("added pitch_flexibility: ")
    assert "within the noise" in j["headline"] and "black box" in j["headline"]
    for f in j["findings"]:
        assert set(f) == {"kind", "runs", "what", "numbers", "action"}
    added = [f for f in j["findings"] if f["kind"] == "effect_added"]
    assert len(added) == 1 and added[0]["action"].endswith("(--with pitch_flexibility)")
    assert added[0]["numbers"]["error_after"] == pytest.approx(d.final_error)
    text = d.report()
    assert "headline: added pitch_flexibility" in text and "verdict:" not in text
    assert "verdict:" in d.report(verbose=True)


def test_a_missing_nonlinearity_is_beyond_and_the_model_with_it_is_not():
    """Actuator friction hidden (a truth the test's helper simulates on the virtual
    table): compared without it, much of the held-out residual is incoherent with the
    command (beyond: nonlinearity); with it, the beyond part falls to the noise's scale."""
    _, runs = effect_campaign(("actuator_friction",))
    without = ModelComparison.of(TableModel([]).fit(runs)).limits
    with_it = ModelComparison.of(TableModel(["actuator_friction"]).fit(runs)).limits
    assert without.beyond > 2 * without.noise
    assert with_it.beyond < 0.5 * without.beyond
    assert with_it.bound < without.bound


def test_headline_names_what_fits_and_counts_the_rest():
    many = [f"a_user_effect_with_a_long_name_{i}" for i in range(8)]
    h = headline(many, 0.41, 0.05, 0.012, 0.03, 0.08)
    assert len(h) <= HEADLINE_MAX and "more" in h
    assert h.startswith("added a_user_effect_with_a_long_name_0")
    assert "41 % -> 5 %" in h and "noise floor 1.2 %" in h and "bound 3 %" in h
    assert "black box 8 %" in h and "4.2 x the floor" in h
    assert headline([], None, 0.011, 0.01, None, None) == (
        "nothing added: 1.1 % (noise floor 1 %); within the noise")
