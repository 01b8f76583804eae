"""Issue 30: a run file is data. A run whose [specimen] names an OpenSees model file is read
by every verb that reads runs (identify, tf, compare, diagnose, drive) without running that
file: the model's floors, modes and damping are data in the run, written by `vtable
simulate`, the one verb that runs the file (and says so). A run without that data is one
line and exit 2, and the file is still not run. The model file here records every time it
is executed (on import and in build), so a reader that ran it would leave a trace.

Also the fuzz trial's four silent leftovers, each a note or a one-line error."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import run_cli

from vtable.runs import read_run
from vtable.runs.hdf5 import read_hdf5, write_hdf5

#: an elastic one-storey OpenSees column (kip, in) that appends to TRACE whenever it runs
MODEL = '''
from pathlib import Path
TRACE = Path(__file__).with_name("executed.txt")
with TRACE.open("a") as fh:
    fh.write("imported\\n")


def build(ops):
    with TRACE.open("a") as fh:
        fh.write("built\\n")
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    ops.node(1, 0.0, 0.0)
    ops.node(2, 0.0, 100.0)
    ops.fix(1, 1, 1, 1)
    ops.mass(2, 0.08, 0.08, 0.0)
    ops.geomTransf("Linear", 1)
    ops.element("elasticBeamColumn", 1, 1, 2, 10.0, 29000.0, 20.0 * 100.0**3 / 87000.0, 1)
    ops.rayleigh(0.0, 0.0, 0.0, 0.0024)
    return {"base": [1], "floors": [[2]], "units": "kip-in"}
'''


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> dict:
    """`vtable simulate` of the column under a 10 s random command: the run, what it
    printed, and the trace the model file left (then cleared)."""
    folder = tmp_path_factory.mktemp("run_is_data")
    (folder / "frame.py").write_text(MODEL)
    (folder / "column.toml").write_text('[specimen]\nkind = "opensees"\nmodel = "frame.py"\n')
    code, out, err = run_cli(["simulate", "--specimen", str(folder / "column.toml"),
                              "--command", "random", "--band", "0", "20", "--peak", "0.1",
                              "--duration", "10", "--out", str(folder / "run")])
    assert code == 0, err
    trace = folder / "executed.txt"
    ran = trace.read_text()
    trace.unlink()
    return {"folder": folder, "out": out, "ran": ran, "trace": trace,
            "run": folder / "run.toml"}


def test_simulate_runs_the_model_and_says_so(made):
    assert "built" in made["ran"]
    assert re.search(r"runs frame\.py, Python", made["out"]), made["out"]
    text = made["run"].read_text()
    for key in ("weights_kip", "heights_in", "frequencies_hz", "damping"):
        assert re.search(rf"^{key} = ", text, re.M), key


def test_the_model_as_data_is_the_models(made):
    """Its floor weight (0.08 kip s²/in x g = 30.9 kip), its height (100 in above the top,
    + 29.7 in to the actuator line), its frequency (√(k/m)/2π with k = 3EI/L³ = 20 kip/in,
    2.517 Hz) and its Rayleigh damping (β ω/2 = 0.0024 x 15.81 / 2 = 1.90 %)."""
    spec = read_run(made["run"]).declared.specimen
    assert spec.n == 1
    assert spec.weights[0] / 4448.2216 == pytest.approx(0.08 * 386.0886, rel=1e-4)
    assert spec.heights[0] / 0.0254 == pytest.approx(129.7, rel=1e-6)
    w = (20.0 / 0.08) ** 0.5
    assert spec.frequencies[0] == pytest.approx(w / (2 * 3.141592653589793), rel=2e-3)
    assert spec.damping == pytest.approx(0.0024 * w / 2, rel=2e-3)


READERS = {
    "identify": lambda p: ["identify", p],
    "tf": lambda p: ["tf", p, "--in", "h_span", "--out", "avg_hdisp"],
    "compare": lambda p: ["compare", p, "--calibrate", "none"],
    "diagnose": lambda p: ["diagnose", p, "--effects", "valve_dynamics", "--max-rounds", "1",
                           "--calibrate", "none"],
    "drive": lambda p: ["drive", p, "--target", "elcentro", "--target-peak", "1",
                        "--calibrate", "none", "--out", str(Path(p).with_name("drv"))],
}


@pytest.mark.parametrize("verb", list(READERS))
def test_a_reader_never_runs_the_model_file(made, verb):
    code, out, err = run_cli(READERS[verb](str(made["run"])))
    assert code == 0, err
    assert not made["trace"].exists(), f"{verb} ran frame.py"
    if verb in ("identify", "tf"):
        assert "frame.py is not run" in out, out


@pytest.mark.parametrize("verb", list(READERS))
def test_a_run_without_the_data_is_one_line_and_runs_nothing(made, verb):
    """The run as the README's examples wrote it before: only `model` in [specimen]."""
    folder = made["folder"]
    p = folder / "bare.toml"
    text = made["run"].read_text()
    p.write_text(re.sub(r"^(weights_kip|heights_in|frequencies_hz|damping) = .*\n", "", text,
                        flags=re.M))
    shutil.copy(made["run"].with_suffix(".csv"), p.with_suffix(".csv"))
    code, _, err = run_cli(READERS[verb](str(p)))
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "bare.toml [specimen]" in err and "vtable simulate" in err, err
    assert not made["trace"].exists(), f"{verb} ran frame.py"


def test_half_the_data_is_an_error_naming_the_rest(made):
    p = made["folder"] / "half.toml"
    p.write_text(re.sub(r"^frequencies_hz = .*\n", "", made["run"].read_text(), flags=re.M))
    shutil.copy(made["run"].with_suffix(".csv"), p.with_suffix(".csv"))
    code, _, err = run_cli(["tf", str(p)])
    assert code == 2 and "frequencies_hz" in err and "half.toml" in err, err
    assert not made["trace"].exists()


# ---- the fuzz trial's leftovers --------------------------------------------------------

@pytest.fixture(scope="module")
def plain_run(made) -> Path:
    """The same channels declared as a bare table (no specimen), for the leftovers."""
    folder = made["folder"]
    p = folder / "plain.toml"
    text = re.sub(r"\[specimen\]\n(?:[^\[\n].*\n)*", '[specimen]\nkind = "none"\n',
                  made["run"].read_text(), count=1)
    p.write_text(text)
    shutil.copy(made["run"].with_suffix(".csv"), p.with_suffix(".csv"))
    return p


def test_an_unknown_knob_is_said_by_tf(plain_run, tmp_path):
    text = re.sub(r"^horizontal = \{ (gain .*) \}", r"horizontal = { \1, boost = 11 }",
                  plain_run.read_text(), count=1, flags=re.M)
    assert "boost = 11" in text
    p = tmp_path / "boost.toml"
    p.write_text(text)
    shutil.copy(plain_run.with_suffix(".csv"), p.with_suffix(".csv"))
    for path in (p, write_hdf5(read_run(p), tmp_path / "boost.h5")):
        code, out, err = run_cli(["tf", str(path), "--in", "h_span", "--out", "avg_hdisp"])
        assert code == 0, err
        assert "unknown knob 'boost'" in out, out


def test_an_hdf5_run_whose_units_table_is_renamed_is_said(plain_run, tmp_path):
    import h5py

    h5 = write_hdf5(read_run(plain_run), tmp_path / "r.h5")
    assert not [n for n in read_hdf5(h5).reports if "names no unit" in n]
    with h5py.File(h5, "r+") as f:
        f.attrs["toml"] = f.attrs["toml"].replace("[units]", "[unit_table]")
    notes = read_hdf5(h5).reports
    assert any("unknown key 'unit_table'" in n for n in notes), notes
    said = [n for n in notes if "names no unit for" in n]
    assert len(said) == 1 and "h_span" in said[0] and "format's units" in said[0], notes


def test_a_vanishing_loop_gain_is_one_line(tmp_path):
    """k_o = 1e-300 1/s is refused naming the key; a small but real gain (1e-3 1/s) whose
    |L| never reaches 1 says there is no phase margin instead of 'inf deg at nan Hz'."""
    f = tmp_path / "tiny.toml"
    f.write_text('model = "servo"\n[parameters]\nf_o_hz = 9.6\nxi_o = 0.606\n'
                 'k_o_per_s = 1e-300\n')
    code, out, err = run_cli(["margins", str(f)])
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "k_o_per_s" in err and "1e-300" in err, err
    f.write_text(f.read_text().replace("1e-300", "1e-3"))
    code, out, err = run_cli(["margins", str(f)])
    assert code == 0, err
    assert "inf" not in out and "nan" not in out, out
    assert "phase margin none" in out and "7.311e+04" in out, out  # 1/|L| at 9.6 Hz


def test_time_declared_in_ms_asks(plain_run, tmp_path):
    """A 200 Hz run declared in ms reads as 200 kHz (as declared) with a note asking."""
    text = plain_run.read_text()
    text = text.replace("[units]\n", '[units]\ntime = "ms"\n') if "[units]" in text \
        else text + '\n[units]\ntime = "ms"\n'
    p = tmp_path / "ms.toml"
    p.write_text(text)
    shutil.copy(plain_run.with_suffix(".csv"), p.with_suffix(".csv"))
    run = read_run(p)
    assert run.fs == pytest.approx(200e3, rel=1e-6)
    said = [n for n in run.reports if "is 'time' in ms?" in n]
    assert len(said) == 1 and "200 Hz" in said[0], run.reports
    assert not [n for n in read_run(plain_run).reports if "is 'time' in" in n]


def test_a_run_shipped_compressed_is_read_and_said(plain_run, tmp_path):
    """RUN.csv.gz beside RUN.toml (no RUN.csv) is read as RUN.csv would be, with a note;
    a broken one is one line naming it."""
    import gzip

    p = tmp_path / "packed.toml"
    p.write_text(plain_run.read_text())
    p.with_suffix(".csv.gz").write_bytes(gzip.compress(plain_run.with_suffix(".csv")
                                                       .read_bytes()))
    a, b = read_run(plain_run), read_run(p)
    assert a.channels.keys() == b.channels.keys()
    for c in a.channels:
        np.testing.assert_array_equal(a.channel(c), b.channel(c))
    assert any("packed.csv.gz: read compressed (gzip)" in n for n in b.reports), b.reports
    p.with_suffix(".csv.gz").write_bytes(b"\x1f\x8b\x08\x00broken")
    code, _, err = run_cli(["tf", str(p), "--in", "h_span", "--out", "avg_hdisp"])
    assert code == 2 and len(err.strip().splitlines()) == 1 and "packed.csv.gz" in err, err
