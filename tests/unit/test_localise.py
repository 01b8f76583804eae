"""Where a model fails by band (`compare(..., detail=True)`): the numbers, and the measured
side worked out once per run however many models are localised on it."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
from conftest import effect_campaign

from vtable.diagnose.compare import compare, group_signal, run_groups

cmp_module = importlib.import_module("vtable.diagnose.compare")


def _scaled(runs, s: float) -> dict:
    """A 'prediction' that is each measured group times `s`."""
    out = {}
    for r in runs:
        out[r.name] = {}
        for g, chans in run_groups(r).items():
            y = group_signal(r, g)
            for c in chans:
                if r.has(c) and y is not None:
                    out[r.name][c] = s * y
    return out


def test_band_errors_are_the_relative_tf_difference_and_the_measured_side_is_kept(monkeypatch):
    """A prediction s times the measured signal has the H1 s H from the command: its band
    error |sH - H| / |H| is |s - 1| in every band, whatever the coherence. A second model
    localised on the same runs with the same memo (a diagnosis's) computes no measured
    transfer function again; without a memo every call starts afresh (a run changed since
    is read as it is now)."""
    _, runs = effect_campaign(("pitch_flexibility",))
    runs = runs[:2]
    calls = []
    real = cmp_module.transfer_function
    monkeypatch.setattr(cmp_module, "transfer_function",
                        lambda *a, **k: calls.append(1) or real(*a, **k))
    memo: dict = {}
    first = compare(_scaled(runs, 1.1), runs, detail=True, memo=memo)
    n_first = len(calls)
    second = compare(_scaled(runs, 0.8), runs, detail=True, memo=memo)
    assert n_first > 0 and len(calls) == n_first
    for c, s in ((first, 1.1), (second, 0.8)):
        values = [v for bands in c.bands.values() for v in bands.values()]
        assert len(values) >= 10
        assert values == pytest.approx([abs(s - 1)] * len(values), rel=1e-9)
    assert np.isclose(second.error, 0.2, rtol=1e-9)
    compare(_scaled(runs, 0.8), runs, detail=True)
    assert len(calls) == 2 * n_first
