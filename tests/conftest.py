"""Shared, cached fixtures: expensive virtual-table runs are made once per test session."""

from __future__ import annotations

import functools

import numpy as np
import pytest

PERIOD = 20.48  # s: 4096 samples at the 200 Hz output rate
RMS_IN = 0.0003  # small-signal periodic random: the linear regime of the multibody table


@functools.cache
def virtual():
    from vtable.params.virtual import virtual_table

    return virtual_table()


@functools.cache
def periodic_random_run(specimen: str | None):
    """Four periods of 0-32 Hz periodic random on the virtual table (first one dropped)."""
    from vtable.mjcf import build
    from vtable.params import presets
    from vtable.signals import band_limited_random
    from vtable.sim import Simulator
    from vtable.units import to_si

    spec = presets.specimen(specimen) if specimen else None
    built = build(virtual(), spec)
    t, x = band_limited_random(4 * PERIOD, 0.001, (0.0, 32.0), rms=to_si(RMS_IN, "in"), seed=1,
                               period=PERIOD)
    res = Simulator(built).run(t, {"x": x}, output_dt=0.005)
    keep = res.t >= PERIOD - 1e-9
    n = 3 * 4096
    return res, keep.nonzero()[0][:n]


@pytest.fixture(scope="session")
def vt():
    return virtual()


def relative_errors(H, Ha):
    return np.abs(np.abs(H) / np.abs(Ha) - 1), np.abs(np.degrees(np.angle(H / Ha)))
