"""The diagnosis report's figures (viz/diagnosis_report.py): MATLAB compare's fit %, the
H1 magnitude's random error (Bendat & Piersol eq 9.90) against a Monte Carlo of H1 on white
noise through a known filter, and the frames chosen."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal as sg

from vtable.ident.tf import transfer_function
from vtable.viz.diagnosis_report import bode_frames, fit_percent, magnitude_band


def test_fit_percent_is_matlab_compares():
    y = np.sin(np.linspace(0, 20, 500))
    assert fit_percent(y, y) == pytest.approx(100.0)
    assert fit_percent(y, np.zeros_like(y) + y.mean()) == pytest.approx(0.0, abs=1e-12)
    assert fit_percent(y, 0.9 * y) == pytest.approx(90.0, rel=1e-3)  # ‖0.1 y‖/‖y‖


def test_the_magnitude_band_is_the_spread_of_h1_over_repeated_records():
    rng = np.random.default_rng(0)
    b, a = sg.butter(2, 10.0, fs=200.0)
    f0, mags, eps = 40, [], []  # the line at 40 x Δf
    for _ in range(200):
        x = rng.standard_normal(200 * 40)
        y = sg.lfilter(b, a, x) + 0.5 * rng.standard_normal(len(x))  # coherence ~0.8
        tf = transfer_function(x, y, 200.0, 1024)
        mags.append(abs(tf.H[f0]))
        eps.append(magnitude_band(tf.H[f0:f0 + 1], tf.coherence[f0:f0 + 1], tf.averages)[0])
    spread = np.std(mags) / np.mean(mags)
    assert np.median(eps) == pytest.approx(spread, rel=0.25), (np.median(eps), spread)


@pytest.mark.parametrize("n, fs, want", [(164 * 200, 200.0, 2048), (11 * 200, 200.0, 256),
                                         (60 * 256, 256.0, 2048)])
def test_frames_are_the_finest_with_eight_averages(n, fs, want):
    nper = bode_frames(n, fs)
    assert nper == want and 2 * n // nper - 1 >= 8


def test_frames_resolve_the_declared_mode():
    """The README's 11 s run at 200 Hz declaring the SDOF frame (2.87 Hz, ξ 0.01): 1024-
    point frames (0.195 Hz, 3 averages) that hold the fit of its mode, not the 0.78 Hz
    lines of 8 averages that hide the peak and notch (issue 19); a run too short to hold
    it falls back to the averages' rule."""
    assert bode_frames(11 * 200, 200.0, (2.87, 0.01)) == 1024
    assert bode_frames(11 * 200, 200.0, None) == 256
    assert bode_frames(400, 200.0, (0.3, 0.01)) == bode_frames(400, 200.0)
