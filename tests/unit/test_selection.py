"""The statistics the diagnosis selects effects by (vtable.diagnose.compare): the noise
floor measured on the held-out segments, and the held-out gain with the standard error
the noise alone gives it — checked against closed forms and Monte Carlo, on runs built
here with known noise."""

from __future__ import annotations

import numpy as np
import pytest

from vtable.diagnose.compare import (
    channel_noise,
    group_noise,
    held_out_gain,
    noise_floor,
    segments,
)
from vtable.runs.model import Run

FS = 200.0
N = 4000  # 20 s


def _run(channels: dict[str, np.ndarray], name: str = "r") -> Run:
    t = np.arange(N) / FS
    return Run(name, t, channels, {k: "in" for k in channels},
               {"specimen": {"kind": "sdof", "weight_kip": 68.0, "height_in": 219.0,
                             "frequency_hz": 2.87, "damping": 0.02}})


def _decaying(seed: int = 0) -> np.ndarray:
    """A 2 Hz motion whose envelope falls tenfold over the run (an earthquake's coda)."""
    t = np.arange(N) / FS
    return np.exp(-np.log(10) * t / t[-1]) * np.sin(2 * np.pi * 2.0 * t + seed)


def test_the_floor_is_the_noise_over_the_held_out_signal():
    rng = np.random.default_rng(1)
    s = 0.01 * _decaying()
    sigma = 2e-4
    a = s + sigma * rng.standard_normal(N)
    b = s + sigma * rng.standard_normal(N)  # the second potentiometer
    run = _run({"h_span": s, "pot_n_sw": a, "pot_n_se": b})
    est = channel_noise(run)
    assert est["pot_n_sw"] == pytest.approx(sigma, rel=0.05)
    # the group averages two sensors: sigma / sqrt(2)
    g = group_noise(run)["structure displacement"]
    assert g == pytest.approx(sigma / np.sqrt(2), rel=0.05)
    _, ho = segments(run)
    y = 0.5 * (a + b)
    held = noise_floor([run], "held")
    assert held == pytest.approx(g / np.sqrt(np.mean(y[ho] ** 2)), rel=1e-9)
    whole = noise_floor([run], "all")
    assert whole == pytest.approx(g / np.sqrt(np.mean(y**2)), rel=1e-9)
    # the same noise on the weak held-out tail costs more than over the whole run
    assert held > 2.5 * whole


def test_a_channel_without_a_pair_takes_the_pairs_relative_noise():
    rng = np.random.default_rng(2)
    s = 0.01 * _decaying()
    x = 0.3 * np.sin(2 * np.pi * 1.3 * np.arange(N) / FS)
    rel = 0.02
    a = s + rel * np.sqrt(np.mean(s**2)) * rng.standard_normal(N)
    b = s + rel * np.sqrt(np.mean(s**2)) * rng.standard_normal(N)
    v = x + rel * np.sqrt(np.mean(x**2)) * rng.standard_normal(N)
    run = _run({"h_span": s, "pot_n_sw": a, "pot_n_se": b, "h_vel": v})
    est = channel_noise(run)
    assert est["h_vel"] == pytest.approx(rel * np.sqrt(np.mean(v**2)), rel=0.06)


def test_the_gains_standard_error_is_what_the_noise_does():
    """Two fixed predictions equally wrong (s + d and s - d) scored on many noise draws:
    the gain is the noise's alone, its mean 0 and its spread `se` (the null hypothesis the
    selection tests against); a prediction really closer to the signal stands many `se`
    above it."""
    rng = np.random.default_rng(3)
    s = 0.01 * _decaying()
    sigma = 3e-4
    t = np.arange(N) / FS
    d = 6e-4 * np.sin(2 * np.pi * 0.7 * t)
    gains, ses = [], []
    for _ in range(400):
        a = s + sigma * rng.standard_normal(N)
        b = s + sigma * rng.standard_normal(N)
        run = _run({"h_span": s, "pot_n_sw": a, "pot_n_se": b})
        noise = {"r": group_noise(run)}
        g = held_out_gain({"r": {"pot_n_sw": s + d, "pot_n_se": s + d}},
                          {"r": {"pot_n_sw": s - d, "pot_n_se": s - d}}, [run], noise)
        gains.append(g.gain)
        ses.append(g.se)
    se = float(np.mean(ses))
    assert np.std(gains) == pytest.approx(se, rel=0.1)
    assert abs(np.mean(gains)) < 3 * se / np.sqrt(len(gains))
    # the same draws' last run: the candidate s + d/3 misses much less than s + d
    better = held_out_gain({"r": {"pot_n_sw": s + d, "pot_n_se": s + d}},
                           {"r": {"pot_n_sw": s + d / 3, "pot_n_se": s + d / 3}}, [run], noise)
    assert better.z > 20 and better.share > 0.5


def test_identical_predictions_gain_nothing():
    rng = np.random.default_rng(4)
    s = 0.01 * _decaying()
    a = s + 1e-4 * rng.standard_normal(N)
    b = s + 1e-4 * rng.standard_normal(N)
    run = _run({"h_span": s, "pot_n_sw": a, "pot_n_se": b})
    p = {"r": {"pot_n_sw": s, "pot_n_se": s}}
    g = held_out_gain(p, p, [run], {"r": group_noise(run)})
    assert g.gain == 0.0 and g.se == 0.0 and g.z == 0.0
    # the model is the truth: what is left is the noise alone
    assert g.e2_current == pytest.approx(g.f2, rel=0.1)
    assert g.systematic < 0.1 * g.f2


def test_a_gain_beyond_a_million_standard_errors_is_said_not_printed():
    """Issue 19: on nearly noise-free runs z reaches 10^18; the text says so instead."""
    from vtable.diagnose.statistics import Gain, standard_errors

    assert standard_errors(4.66) == "4.7 standard errors of the noise"
    assert standard_errors(-1e6) == "-1000000.0 standard errors of the noise"
    big = standard_errors(1.9e18)
    assert big.startswith("more than +10^6 standard errors") and "noise-free" in big
    assert standard_errors(-2.9e9).startswith("less than -10^6 standard errors")
    g = Gain(e2_current=0.02, e2_candidate=0.01, f2=1e-12, se=1e-14)
    assert g.z == pytest.approx(1e12) and g.z_text == big
