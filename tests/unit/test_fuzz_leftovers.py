"""Issue 19's fuzz leftovers, each answered in one line with exit code 2 (or, for an
attribute nobody reads, a note): a run whose time step is 1e-9 s, a rigid specimen of
negative count or size, a command of 1e-300 in, a CSV given where its run file is wanted,
an HDF5 run with an attribute the format does not have; and a rigid specimen on a run that
measured a structure (its structure channels are not scored, said so, not a traceback).
A later trial's find: a model whose rocking stiffness is 1e-300 lb·in/rad has its margins
said without a NumPy warning.
The base run comes from the independent truth simulator (tests/truth)."""

from __future__ import annotations

import os
import re
from pathlib import Path

import h5py
import pytest
import truth
from conftest import run_cli

from vtable.runs import read_run
from vtable.runs.hdf5 import read_hdf5, write_hdf5


@pytest.fixture(scope="module")
def base(tmp_path_factory) -> Path:
    """A 4 s truth run (SDOF frame, 200 Hz, 1 % noise): its TOML path."""
    stem = tmp_path_factory.mktemp("leftovers") / "base"
    spec = truth.sdof(weight_kip=68.4, height_in=219.0, f_hz=2.87, xi=0.01)
    cmd = truth.random_command(4.05, (0.0, 20.0), peak_in=0.2, seed=3)
    res = truth.simulate(truth.eerc_table(pitch="hybrid"), spec, cmd, fs=200.0)
    truth.write_run(stem, res, spec, noise=0.01, seed=2)
    return stem.with_suffix(".toml")


def _variant(base: Path, name: str, toml=None, csv=None) -> str:
    """A copy of the base run with its TOML and CSV texts changed by the functions given."""
    t, c = base.read_text(), base.with_suffix(".csv").read_text()
    p = base.parent / f"{name}.toml"
    p.write_text(toml(t) if toml else t)
    p.with_suffix(".csv").write_text(csv(c) if csv else c)
    return str(p)


def _one_line_error(code: int, err: str, *names: str) -> None:
    assert code == 2, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for n in names:
        assert n in err, (n, err)


def _column(csv: str, k: int, f) -> str:
    """The CSV with column `k` of every data row mapped by f(row index, value)."""
    lines = csv.splitlines()
    out = [lines[0]]
    for i, row in enumerate(lines[1:]):
        v = row.split(",")
        v[k] = repr(f(i, float(v[k])))
        out.append(",".join(v))
    return "\n".join(out) + "\n"


def _rigid(extra: str):
    return lambda t: re.sub(r"\[specimen\]\n(?:[^\[\n].*\n|\n)*",
                            f'[specimen]\nkind = "rigid"\nweight_kip = 20\nheight_in = 40\n'
                            f"{extra}\n", t, count=1)


@pytest.mark.parametrize("verb", ["compare", "diagnose"])
def test_a_nanosecond_time_step_is_refused_with_a_hint(base, verb):
    p = _variant(base, "tiny_dt", csv=lambda c: _column(c, 0, lambda i, _: i * 1e-9))
    code, _, err = run_cli([verb, p])
    _one_line_error(code, err, "tiny_dt", "'time'", "1e+09 Hz", "seconds")


@pytest.mark.parametrize("extra, names", [("count = -2", ("count", "-2")),
                                          ("count = 0", ("count", "0")),
                                          ("size_in = [-10, 20, 30]", ("size_in", "-10")),
                                          ("size_in = [10, 20]", ("size_in", "3 numbers"))])
def test_a_rigid_specimen_of_no_blocks_or_negative_size_is_refused(base, extra, names):
    code, _, err = run_cli(["compare", _variant(base, "rigid_bad", toml=_rigid(extra))])
    _one_line_error(code, err, "rigid_bad.toml", "[specimen]", *names)


def test_a_rigid_specimen_on_a_measured_structure_leaves_its_channels_unscored(base):
    code, out, err = run_cli(["compare", _variant(base, "rigid_ok", toml=_rigid(""))])
    assert code == 0, err
    assert "predicts no structure motion" in out and "acc_n_ne" in out, out


def test_a_command_of_1e_300_drives_nothing(base):
    k = base.with_suffix(".csv").read_text().splitlines()[0].split(",").index("h_span")
    p = _variant(base, "tiny_cmd", csv=lambda c: _column(c, k, lambda _, v: v * 1e-300))
    code, out, err = run_cli(["tf", p, "--in", "h_span", "--out", "avg_hdisp"])
    _one_line_error(code, err, "h_span", "drives nothing")
    assert "inf" not in out


def test_the_csv_given_for_the_run_file(base):
    code, out, err = run_cli(["tf", str(base.with_suffix(".csv"))])
    assert code == 0 and "H1" in out, err  # read through the TOML beside it
    lone = base.parent / "lone.csv"
    lone.write_text(base.with_suffix(".csv").read_text())
    code, _, err = run_cli(["tf", str(lone)])
    _one_line_error(code, err, "lone.csv", "lone.toml", "not beside it")


def test_an_hdf5_attribute_the_format_does_not_have_is_said(base, tmp_path):
    h5 = tmp_path / "run.h5"
    write_hdf5(read_run(base), h5)
    assert not [n for n in read_hdf5(h5).reports if "attribute" in n]
    with h5py.File(h5, "r+") as f:
        f.attrs["units"] = 5
    notes = [n for n in read_hdf5(h5).reports if "attribute 'units' not read" in n]
    assert len(notes) == 1 and "[units] table in 'toml'" in notes[0]


@pytest.fixture(scope="module")
def long_campaign(tmp_path_factory) -> list[str]:
    """Three 20 s truth runs: a diagnosis of them takes well over 10 s."""
    folder = tmp_path_factory.mktemp("sigint")
    spec = truth.sdof(weight_kip=68.4, height_in=219.0, f_hz=2.87, xi=0.01)
    paths = []
    for k, peak in enumerate((0.1, 0.2, 0.3)):
        cmd = truth.random_command(20.05, (0.0, 20.0), peak_in=peak, seed=10 + k)
        table = truth.eerc_table(pitch="hybrid", effects={"actuator_friction": {"friction": 2}})
        res = truth.simulate(table, spec, cmd, fs=200.0)
        truth.write_run(folder / f"r{k}", res, spec, noise=0.01, seed=20 + k)
        paths.append(str(folder / f"r{k}.toml"))
    return paths


def _python_started(pid: int, timeout: float = 30.0) -> None:
    """Wait until the process `pid` runs vtable's own code: numpy's extension is mapped
    (Python's start-up, its `site` import, is over: a Ctrl-C before that is Python's own
    fatal error, whatever the program; on a loaded machine it lasted past 0.3 s)."""
    import time

    maps = Path(f"/proc/{pid}/maps")
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            if "_multiarray_umath" in maps.read_text():
                return
        except OSError:  # no /proc here, or the process has ended
            return
        time.sleep(0.01)


#: seconds into `vtable diagnose` (from its first import of numpy) at which Ctrl-C is
#: pressed: while the process imports, while its Dask workers are forked, fitting the
#: starting model, in the rounds
CTRL_C_AT = (0.3, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 7.0)


def test_ctrl_c_into_diagnose_is_one_line_and_exit_130(long_campaign):
    """Ctrl-C as a terminal sends it, to the whole process group (the diagnosis and its
    forked Dask workers), at many moments: one line ('vtable: interrupted ...', or the
    plain interruption before the diagnosis has begun) and exit code 130 every time, no
    traceback from any process. Issue 19's version interrupted the parent alone; a group
    interrupt printed two worker tracebacks (issue 33)."""
    import os
    import signal
    import subprocess
    import time

    from conftest import vtable_exe

    landed = 0
    for after in CTRL_C_AT:
        p = subprocess.Popen([*vtable_exe(), "diagnose", *long_campaign], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True, start_new_session=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        _python_started(p.pid)
        time.sleep(after)
        if p.poll() is not None:  # done before the interrupt: nothing to test there
            p.communicate()
            continue
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=60)
        lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("[")]
        assert p.returncode == 130, (after, err)
        assert "Traceback" not in err and len(lines) == 1, (after, err)
        assert lines[0].startswith("vtable: interrupted"), (after, err)
        landed += 1
    assert landed >= 5, landed


def test_the_local_clusters_logs_stay_silent_while_it_closes():
    """A scatter that Ctrl-C cut short failed in the scheduler as the workers left, and
    distributed logged its traceback once the closing cluster had given its log handlers
    their levels back (one run of the test above, under a full suite's load); in another
    run (a clean-clone CI's), the scheduler's task re-raised it and asyncio printed the
    exception nobody retrieved. An error logged at the very end of the cluster's close and
    a task of the cluster's event loop that fails unawaited stay unprinted, and
    distributed's own level is given back once `shutdown` has closed it."""
    import subprocess
    import sys

    code = ("import asyncio, gc, logging, time\n"
            "from distributed.deploy.spec import SpecCluster\n"
            "from vtable.diagnose import workers\n"
            "closing = SpecCluster._close\n"
            "async def late(self):\n"
            "    await closing(self)  # the handlers' levels given back here\n"
            "    logging.getLogger('distributed.core').error('a late error')\n"
            "SpecCluster._close = late\n"
            "before = logging.getLogger('distributed').level\n"
            "client = workers.cluster(2)\n"
            "async def lost():\n"
            "    raise KeyError('a lost task')\n"
            "def lose():  # a task of the loop's that fails, then is collected unawaited\n"
            "    tasks = []\n"
            "    client.loop.add_callback(lambda: tasks.append(asyncio.ensure_future(lost())))\n"
            "    while not (tasks and tasks[0].done()):\n"
            "        time.sleep(0.01)\n"
            "    tasks.clear()\n"
            "    gc.collect()\n"
            "lose()\n"
            "workers.shutdown()\n"
            "print(logging.getLogger('distributed').level == before)\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0 and p.stdout.strip() == "True", (p.stdout, p.stderr)
    assert "a late error" not in p.stderr and "a lost task" not in p.stderr, p.stderr


def test_the_command_starts_no_second_python_interpreter(tmp_path):
    """`vtable` does not look for MuJoCo's OpenGL back-end (it renders nothing with it): the
    search ran `python -c` to read GLFW's version, a second interpreter that Ctrl-C, sent to
    the process group while it started, ended with "Fatal Python error: init_import_site"
    and a traceback (CI of stop 40, Ctrl-C 2 s into `vtable diagnose`)."""
    import json
    import subprocess
    import sys

    probe = tmp_path / "probe.py"
    probe.write_text(
        "import atexit, json, subprocess, sys\n"
        "started = []\n"
        "real = subprocess.Popen.__init__\n"
        "def record(self, args, *a, **k):\n"
        "    started.append([str(x) for x in ([args] if isinstance(args, str) else args)])\n"
        "    return real(self, args, *a, **k)\n"
        "subprocess.Popen.__init__ = record\n"
        f"sys.argv = ['vtable', 'simulate', '--specimen', 'sdof_frame', '--command', 'random',"
        f" '--band', '0', '20', '--peak', '0.1', '--duration', '1', '--out', "
        f"{str(tmp_path / 'r')!r}]\n"
        "atexit.register(lambda: print(json.dumps([started, 'mujoco' in sys.modules]),\n"
        "                              file=sys.stderr))  # run ends the process itself\n"
        "from vtable.__main__ import run\n"
        "run()\n")
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    p = subprocess.run([sys.executable, str(probe)], capture_output=True, text=True, env=env,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    started, loaded = json.loads(p.stderr.strip().splitlines()[-1])
    assert loaded, "the simulation did not load MuJoCo: nothing was tested"
    pythons = [a for a in started if a and Path(a[0]).name.startswith("python")]
    assert not pythons, pythons


def test_ctrl_c_while_numba_compiles_a_force_law_is_not_taken_for_a_typing_error(monkeypatch):
    """A Ctrl-C pending while numba compiles comes back as a SystemError chained to it; the
    reduced model's fallback for a law numba cannot type (run it as Python) must not take
    it for one: the interrupt goes on (a cold cache's first diagnosis lost it, exit 0)."""
    from vtable.hydraulics.law import ServoLaw
    from vtable.models.physics import Physics, nominal_open_loop
    from vtable.models.reduced import ReducedModel
    from vtable.params import presets

    real = ServoLaw.composition

    def pending(self, extra=(), elements=(), switchable=()):
        if elements:
            try:
                raise KeyboardInterrupt
            except KeyboardInterrupt as e:
                raise SystemError("error return without exception set") from e
        return real(self, extra, elements, switchable)

    monkeypatch.setattr(ServoLaw, "composition", pending)
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"), {"storey_yield": {}})
    with pytest.raises(KeyboardInterrupt):
        ReducedModel(ph)
    monkeypatch.setattr(ServoLaw, "composition", real)
    assert not ReducedModel(ph).python  # without the interrupt, the law compiles


#: a three-storey building on the hybrid table (the fuzz trial's "mdof" model), its rocking
#: stiffness nearly zero
NEARLY_NO_ROCKING = (
    'model = "mdof_hybrid"\n[building]\nweights_kip = [20.0, 20.0, 20.0]\n'
    'heights_in = [80.0, 150.0, 219.0]\ndamping = 0.02\nfrequencies_hz = [2.0, 6.0, 9.5]\n'
    '[open_loop]\nf_o_hz = 9.6\nxi_o = 0.606\nk_o_per_s = 29.5\n[rocking]\n'
    'k_theta_lb_in_per_rad = 1e-300\nc_theta_lb_in_s_per_rad = 3.7e8\n')


def test_a_nearly_zero_rocking_stiffness_has_its_margins_said_without_a_warning(tmp_path):
    """SciPy's balancing (`vtable.analytic.hold.balance`) casts every scale factor to an
    integer; one beyond an integer's range (the pitch row nearly zero) warned on the
    user's terminal, about a value it never uses. The margins are said, and the balancing
    is SciPy's own."""
    import warnings

    import numpy as np
    import scipy.linalg

    from vtable.analytic.hold import balance

    p = tmp_path / "m.toml"
    p.write_text(NEARLY_NO_ROCKING)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a warning would end the command
        code, out, err = run_cli(["margins", str(p)])
    assert (code, err) == (0, ""), err
    assert re.search(r"gain margin +2\.557 +at 9\.954 Hz", out), out
    A = np.array([[-1.0, 1e-300], [1e300, -2.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Ab, (scale, _) = balance(A, separate=True)
    with np.errstate(invalid="ignore"):
        want = scipy.linalg.matrix_balance(A, permute=False, separate=True)
    assert np.array_equal(Ab, want[0]) and np.array_equal(scale, want[1][0])
