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


@functools.cache
def identification_runs(tmpdir: str):
    """The identification campaign, made once: a bare-table run (0-32 Hz, RC filter off
    so eq 6.16 applies) and a long SDOF-frame run (0-25 Hz), written as run files."""
    from vtable.runs import read_run
    from vtable.sim.experiment import load_specimen, make_command, run_experiment

    out = {}
    bare = make_command("random", duration=120.0, band=(0.0, 32.0), peak_in=0.05, seed=7)
    run_experiment(load_specimen("none"), bare, out=f"{tmpdir}/bare", rc_filter=False)
    out["bare"] = read_run(f"{tmpdir}/bare.toml")
    sdof = make_command("random", duration=420.0, band=(0.0, 25.0), peak_in=0.2, seed=5)
    run_experiment(load_specimen("sdof_frame"), sdof, out=f"{tmpdir}/sdof")
    out["sdof"] = read_run(f"{tmpdir}/sdof.toml")
    return out


@pytest.fixture(scope="session")
def ident_runs(tmp_path_factory):
    return identification_runs(str(tmp_path_factory.mktemp("ident")))
