"""A lab's own controller kind from a file (issue 18 deliverable 1): the example
examples/leaky_pi_controller.py (P plus a leaky integral k_i/(s + 1/T_l)) loaded with
`--controller-from`, in the reduced model and the declared closed loop against the hand
derivation (tests/test_truth_controllers.closed_loop with C = p (1 + (k_i/p)/(s + 1/T_l)),
not vtable's code), and through the CLI: simulate writes a run on it, compare reads it
back, and a run naming the kind without the file is one line, exit code 2."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from truth.closed_loop import closed_loop, lnec_constants

from vtable.analytic.controlled import declared_loop
from vtable.cli import main
from vtable.controllers import kinds
from vtable.models.physics import Physics
from vtable.models.reduced import ReducedModel
from vtable.params.specimen import NoSpecimen
from vtable.runs.lab import lab_table
from vtable.runs.table import table_from_dict
from vtable.tables.lab import bare_loop

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "leaky_pi_controller.py"
F = np.array([0.05, 0.3, 1.0, 3.0, 6.0, 10.0, 15.0, 22.0, 30.0])
P, KI, TL = 1.2, 1.5, 4.0
CONTROLLER = {"kind": "leaky_pi", "displacement_gain_v_per_m": 129.93, "p": P,
              "integral_gain_per_s": KI, "leak_time_s": TL}


@pytest.fixture(scope="module")
def table():
    assert kinds.load_file(EXAMPLE) == ["leaky_pi"]
    assert kinds.source_file("leaky_pi") == str(EXAMPLE)
    return lab_table(table_from_dict({"preset": "lnec-st1d", "controller": CONTROLLER}))


def hand(f: np.ndarray) -> np.ndarray:
    s = 2j * math.pi * f
    return closed_loop(s, **lnec_constants(), p=P, Ne=1 + (KI / P) / (s + 1 / TL))


def test_the_lab_kind_is_the_hand_derivation_in_the_reduced_model(table):
    m = ReducedModel(Physics(bare_loop(table), NoSpecimen()), table)
    A, B = m._linear[0], m._linear[1]
    c = np.zeros(A.shape[0])
    c[:m.M.shape[0]] = m.ax
    v = np.array([c @ np.linalg.solve(2j * math.pi * fk * np.eye(len(A)) - A, B) for fk in F])
    h = hand(F)
    assert np.abs(v / h - 1).max() < 1e-6, np.abs(v / h - 1)
    # the integral matters: without it the loop differs by > 1 % somewhere below 1 Hz
    bare = closed_loop(2j * math.pi * F, **lnec_constants(), p=P)
    assert np.abs(bare / h - 1).max() > 0.01


def test_the_lab_kind_in_the_declared_closed_loop(table):
    vt = table
    ol = bare_loop(table)
    h = declared_loop(vt)(F, ol.f_o, ol.xi_o, ol.k_o, 0.0246)
    assert np.abs(h / hand(F) - 1).max() < 0.01


def test_simulate_and_compare_through_the_cli(tmp_path, capsys, table):
    (tmp_path / "lab.toml").write_text(
        '[table]\npreset = "lnec-st1d"\n[table.controller]\n'
        + "".join(f"{k} = {v!r}\n".replace("'", '"') for k, v in CONTROLLER.items()))
    stem = tmp_path / "run"
    code = main(["simulate", "--table", str(tmp_path / "lab.toml"), "--specimen", "none",
                 "--duration", "4", "--controller-from", str(EXAMPLE), "--out", str(stem)])
    assert code == 0, capsys.readouterr().err
    capsys.readouterr()
    from vtable.runs import read_run
    run = read_run(f"{stem}.toml")  # the run names the table it was made on, whole
    assert run.table().controller.kind == "leaky_pi"
    assert run.table().controller.extra == {"integral_gain_per_s": KI, "leak_time_s": TL}
    code = main(["compare", f"{stem}.toml", "--controller-from", str(EXAMPLE), "--json",
                 str(tmp_path / "c.json")])
    assert code == 0, capsys.readouterr().err
    d = json.loads((tmp_path / "c.json").read_text())
    assert d["error"] < 0.01, d["error"]  # the model that made the run reads it back
    # the same run read where the kind is not registered: one line, exit code 2
    saved = kinds.KINDS.snapshot()
    kinds.KINDS.remove("leaky_pi")
    try:
        capsys.readouterr()
        code = main(["compare", f"{stem}.toml"])
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1 and "leaky_pi" in err, err
    finally:
        kinds.KINDS.restore(saved)
