"""A sharp yielding storey (issue 31): the independent truth's own yield law — Bouc–Wen in
its displacement form with n = 8, nearly elastic-perfectly-plastic, yielding at a base
shear of a fraction of the specimen's weight (tests/truth/model.py) — found by a plain
`diagnose` as `storey_yield` with its sharpness n fitted, the yield drift and α the
truth's, within the noise; and a rounded one (n = 2) keeps n = 2.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import pytest
import truth

from vtable.diagnose.engine import Diagnoser
from vtable.runs import read_run

K_SDOF = 68.0 / 386.0886 * (2 * math.pi * 2.87) ** 2  # kip/in: the §2.4 frame's storey


@functools.cache
def _diagnosis(folder: str, fraction: float, alpha: float, rounded: bool = False):
    """The truth's sharp yield law at base shear `fraction` x the weight, or (`rounded`)
    its specimen hysteresis with n = 2 at the same yield drift."""
    u_y = fraction * 68.0 / K_SDOF
    hyst = {"yield_drift_in": u_y, "post_yield_ratio": alpha} if rounded else None
    spec = truth.sdof(68.0, 219.0, 2.87, 0.02, hysteresis=hyst)
    decl = truth.perturb(truth.sdof(68.0, 219.0, 2.87, 0.02), seed=31, frequency=0.03,
                         damping=1.5, weight=0.05)
    effects = {} if rounded else {"yielding_storey": {"yield_fraction": fraction,
                                                      "post_yield_ratio": alpha}}
    table = truth.eerc_table(effects=effects)
    cmds = [("random_0", truth.random_command(12.0, (0, 25), peak_in=0.1, seed=34)),
            ("random_1", truth.random_command(12.0, (0, 25), peak_in=0.5, seed=35)),
            ("earthquake", truth.earthquake_command("elcentro", peak_in=3.0))]
    runs = [read_run(truth.write_run(Path(folder) / name,
                                     truth.simulate(table, spec, cmd, fs=200.0), decl,
                                     noise=0.01, seed=90 + k)[0])
            for k, (name, cmd) in enumerate(cmds)]
    return Diagnoser(runs).diagnose()


def test_a_sharp_yield_is_found_with_its_sharpness(tmp_path_factory):
    d = _diagnosis(str(tmp_path_factory.mktemp("sharp")), 0.8, 0.05)
    assert d.final_effects == ["storey_yield"], d.headline
    p = d.final.effects["storey_yield"]
    assert (p["storey"], p["storeys"]) == (1, 1)
    assert p["sharpness"] == pytest.approx(8.0, rel=0.1)  # the truth's n
    assert p["yield_drift"] == pytest.approx(0.8 * 68.0 / K_SDOF, rel=0.05)
    assert p["post_yield_ratio"] == pytest.approx(0.05, abs=0.01)
    assert d.final_error <= 2 * d.noise_floor, d.headline


def test_a_rounded_yield_keeps_its_sharpness(tmp_path_factory):
    d = _diagnosis(str(tmp_path_factory.mktemp("rounded")), 0.8, 0.05, rounded=True)
    assert d.final_effects == ["storey_yield"], d.headline
    p = d.final.effects["storey_yield"]
    assert p["sharpness"] == pytest.approx(2.0, rel=0.1)
    assert p["yield_drift"] == pytest.approx(0.8 * 68.0 / K_SDOF, rel=0.05)
    assert d.final_error <= 2 * d.noise_floor, d.headline
