"""`identify` on a table carrying a SDOF fits eq 7.9, the report's P loop: when the run
declares a controller with terms beyond P (an integral, feedforward, a reference
generator), the fit cannot hold them, and the result says so instead of quoting k_o as
if the loop were P alone (found on LNEC's measured run: a pid with i_per_s, one with
velocity feedforward and a tvc all gave the same eq 7.9 fit, silently)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.signal as sg

from vtable.ident.report import identify_run
from vtable.runs import read_run

FS = 200.0
TOML = """format = "vtable-run/1"
title = "a table carrying a sdof"

[table]
preset = "lnec-st1d"
{controller}
[specimen]
kind = "sdof"
weight_kip = 2.2
height_in = 40.0
frequency_hz = 3.2
damping = 0.08

[units]
h_span = "mm"
avg_hdisp = "mm"
"""


def _run(tmp: Path, name: str, controller: str) -> Path:
    """60 s of band-limited noise through a loop of k_o 20 1/s, an oil column of 10 Hz
    (ξ 0.4) and the notch a 3.2 Hz specimen makes in x_t/x_c."""
    rng = np.random.default_rng(7)
    t = np.arange(int(60 * FS)) / FS
    b, a = sg.butter(4, 30.0, fs=FS)
    x_c = sg.lfilter(b, a, rng.standard_normal(t.size))
    w = 2 * np.pi * 3.2
    w_o = 2 * np.pi * 10.0
    num = np.polymul([20.0 * w_o * w_o], [1.0, 2 * 0.05 * w, w * w])
    den = np.polymul(np.polymul([1.0, 20.0], [1.0, 2 * 0.3 * w, w * w]),
                     [1.0, 2 * 0.4 * w_o, w_o * w_o])
    _, x_t, _ = sg.lsim((num, den), x_c, t)
    (tmp / f"{name}.toml").write_text(TOML.format(controller=controller))
    np.savetxt(tmp / f"{name}.csv", np.column_stack([t, x_c, x_t]), delimiter=",",
               header="time,h_span,avg_hdisp", comments="", fmt="%.6g")
    return tmp / f"{name}.toml"


@pytest.mark.parametrize("controller, terms", [
    ('[table.controller]\nkind = "pid"\ndisplacement_gain_v_per_m = 129.93\np = 1.0\n'
     'i_per_s = 1.8\n', "i_per_s"),
    ('[table.controller]\nkind = "tvc"\ndisplacement_gain_v_per_m = 129.93\np = 1.0\n'
     'feedforward_velocity_s = 0.05\nreference_frequency_hz = 40.0\n',
     "feedforward_velocity_s, reference generator"),
])
def test_eq_7_9_says_which_declared_terms_it_leaves_out(tmp_path, controller, terms):
    ident = identify_run(read_run(_run(tmp_path, "c", controller)))
    d = ident.to_json()["table_sdof"]
    assert f"terms ({terms}) are not in this fit" in d["note_controller"]
    assert "note: eq 7.9 is the report's P loop" in ident.report()


def test_a_p_controller_needs_no_note(tmp_path):
    ident = identify_run(read_run(_run(tmp_path, "p", "")))
    d = ident.to_json()["table_sdof"]
    assert "note_controller" not in d and np.isfinite(d["params"]["k_o"])
    assert "the report's P loop" not in ident.report()
