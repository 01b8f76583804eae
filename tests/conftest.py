"""Shared, cached fixtures: expensive virtual-table runs are made once per test session."""

from __future__ import annotations

import functools
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest

#: every temporary file and folder of the session (the campaigns tests make once with
#: tempfile.mkdtemp, pytest's tmp_path, the diagnosis workers' campaign files) lives in one
#: folder, removed when the session ends: a run leaves nothing in the system's /tmp
SESSION_TMP = tempfile.mkdtemp(prefix="vtable-tests-")
tempfile.tempdir = SESSION_TMP

#: every `vtable` command a test starts runs in its own process (`vtable.warm`): no warm
#: process outlives the session; tests/unit/test_warm.py starts its own, and stops them
os.environ["VTABLE_WARM"] = "0"


def pytest_sessionfinish(session, exitstatus):
    from vtable.diagnose import workers

    workers.shutdown()  # the Dask workers' scratch folders live in SESSION_TMP too
    tempfile.tempdir = None
    shutil.rmtree(SESSION_TMP, ignore_errors=True)


def _catalog_as_shipped() -> tuple:
    from vtable.effects import registry

    return registry.EFFECTS.snapshot()  # the catalog's own effects, loaded


_SHIPPED = _catalog_as_shipped()


def _restore_catalog() -> None:
    from vtable.effects import registry

    registry.EFFECTS.restore(_SHIPPED)


@pytest.fixture(autouse=True)
def catalog_as_shipped():
    """Every test starts and ends with the catalog as shipped: an effect a test (or a test
    module, when it is collected) registers never becomes a candidate of another test's
    diagnosis (with pytest-xdist every worker collects every module)."""
    _restore_catalog()
    yield
    _restore_catalog()


#: the repository's root, and the documentation's pages in the site's order (mkdocs.yml's
#: nav), the README first: what the tests of the docs read
ROOT = Path(__file__).resolve().parents[1]


def doc_pages() -> list[Path]:
    """README.md, then every page of the site in mkdocs.yml's nav order."""
    import re

    nav = re.findall(r":\s*([\w/-]+\.md)\s*$", (ROOT / "mkdocs.yml").read_text(), re.M)
    return [ROOT / "README.md", *(ROOT / "docs" / p for p in nav)]


def doc_blocks(lang: str, pages: list[Path] | None = None) -> list[tuple[Path, str]]:
    """The fenced ```lang blocks of `pages` (default `doc_pages()`), in order: (page,
    text)."""
    import re

    return [(p, b) for p in (pages or doc_pages())
            for b in re.findall(rf"```{lang}\n(.*?)```", p.read_text(), re.S)]


PERIOD = 20.48  # s: 4096 samples at the 200 Hz output rate
RMS_IN = 0.0003  # small-signal periodic random: the linear regime of the multibody table


@functools.cache
def virtual():
    from vtable.tables.eerc import virtual_table

    return virtual_table()


@functools.cache
def periodic_random_run(specimen: str | None):
    """Four periods of 0-32 Hz periodic random on the virtual table (first one dropped)."""
    from vtable.params import presets
    from vtable.params.specimen import NoSpecimen
    from vtable.signals import Command, band_limited_random
    from vtable.sim import simulate, standard_physics
    from vtable.units import to_si

    spec = presets.specimen(specimen) if specimen else NoSpecimen()
    t, x = band_limited_random(4 * PERIOD, 0.001, (0.0, 32.0), rms=to_si(RMS_IN, "in"), seed=1,
                               period=PERIOD)
    cmd = Command("periodic random", t, x, {"kind": "random", "band_hz": [0.0, 32.0]})
    res = simulate(standard_physics(spec), cmd, 200.0, vt=virtual()).result
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
    from vtable.signals import make_command
    from vtable.sim.experiment import load_specimen, run_experiment

    out = {}
    bare = make_command("random", duration=120.0, band=(0.0, 32.0), peak_in=0.05, seed=7)
    run_experiment(load_specimen("none"), bare, out=f"{tmpdir}/bare", rc_filter=False)
    out["bare"] = read_run(f"{tmpdir}/bare.toml")
    sdof = make_command("random", duration=420.0, band=(0.0, 25.0), peak_in=0.2, seed=5)
    run_experiment(load_specimen("sdof_frame"), sdof, out=f"{tmpdir}/sdof")
    out["sdof"] = read_run(f"{tmpdir}/sdof.toml")
    return out


def shared_temp(tmp_path_factory) -> Path:
    """The temporary folder every pytest-xdist worker of this run shares (their base
    folders' parent), or the run's base folder without xdist."""
    import os

    root = tmp_path_factory.getbasetemp()
    return root.parent if os.environ.get("PYTEST_XDIST_WORKER") else root


def made_once(tmp_path_factory, name: str, make):
    """What `make(folder)` returns, made once per test session by whichever pytest-xdist
    worker asks first, in a folder the workers share (their base folder's parent); the
    others wait for it (a file lock) and read it back (pickled), with any file it wrote
    in `folder`. A module or session fixture is otherwise made by each worker that runs
    one of its tests: LNEC's diagnosis (17-19 s) and the identification campaign (13-14
    s) were each made twice in a suite split across both cores. `make` must not ask for
    the same `name` (it would wait for itself)."""
    import fcntl
    import pickle

    root = shared_temp(tmp_path_factory)
    folder, lock = root / f"made-once-{name}", root / f"made-once-{name}.lock"
    value_file = folder / "value.pickle"
    with open(lock, "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        try:
            if value_file.is_file():
                with open(value_file, "rb") as f:
                    return pickle.load(f)
            shutil.rmtree(folder, ignore_errors=True)  # a make that failed part-way
            folder.mkdir()
            value = make(folder)
            part = value_file.with_suffix(".part")
            with open(part, "wb") as f:
                pickle.dump(value, f)
            part.replace(value_file)
            # read back here too: every worker gets the same, whatever the schedule
            with open(value_file, "rb") as f:
                return pickle.load(f)
        finally:  # released here, not when the file closes: a process `make` forked (a
            # diagnosis's Dask workers, alive till the session ends) holds the file too
            fcntl.flock(held, fcntl.LOCK_UN)


@pytest.fixture(scope="session")
def ident_runs(tmp_path_factory):
    return made_once(tmp_path_factory, "ident", lambda folder: identification_runs(str(folder)))


#: a visible dose of each catalog effect for the hidden-effect campaigns
HIDDEN = {
    "pitch_flexibility": {},
    "force_feedback_filter": {"rc": 0.01},
    "valve_flow_nonlinearity": {"supply_pressure": 3000.0},
    "actuator_friction": {"friction": 3.0},
    "flow_saturation": {"v_max": 10.0},
    "valve_dynamics": {"tau": 0.005},
    "oil_column_air": {"air_ratio": 0.04},
    "amplitude_dependent_damping": {"gamma": 0.03},
    "foundation_compliance": {"f_f": 8.0, "xi_f": 0.1},
    "sensor_filter": {"cutoff_hz": 100.0},
}


@functools.cache
def campaign_commands():
    from vtable.signals import make_command

    return (make_command("random", duration=11.0, band=(0.0, 25.0), peak_in=0.05, seed=1),
            make_command("random", duration=11.0, band=(0.0, 25.0), peak_in=0.15, seed=2),
            make_command("earthquake", peak_in=4.0))


@functools.cache
def effect_campaign(effects: tuple[str, ...]):
    """Three runs of the SDOF frame on the virtual table with `effects` present (doses of
    HIDDEN): random 0-25 Hz at two spans and §9.2 El Centro, 1 % RMS noise, 200 Hz."""
    from vtable.models.physics import Physics, nominal_open_loop
    from vtable.params import presets
    from vtable.sim import simulate

    truth = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                    {e: HIDDEN[e] for e in effects})
    runs = [simulate(truth, c, noise=0.01, seed=10 + i, name=f"run{i}")
            for i, c in enumerate(campaign_commands())]
    return truth, runs


@functools.cache
def effect_diagnosis(effects: tuple[str, ...]):
    from vtable.diagnose.engine import Diagnoser

    truth, runs = effect_campaign(effects)
    d = Diagnoser(runs)
    return truth, d, d.diagnose()


def truth_runs(folder: str, table, spec, decl, cmds, noise: float = 0.01, seed: int = 0,
               fs: float = 200.0) -> list:
    """The runs the independent truth simulator (tests/truth) makes of `spec` on `table`,
    one per (name, command) of `cmds`, written with the declaration `decl` and `noise`
    (seeds from `seed`) into `folder` and read back as a user's files."""
    import truth

    from vtable.runs import read_run

    paths = [truth.write_run(f"{folder}/{name}", truth.simulate(table, spec, cmd, fs=fs), decl,
                             noise=noise, seed=seed + k)[0]
             for k, (name, cmd) in enumerate(cmds)]
    return [read_run(p) for p in paths]


# ---- running the CLI: in this process with a time limit, or as a user does ----------------
HANG_S = 30  # s: a command taking longer than this on the fuzz tests' tiny inputs hangs


class HangError(Exception):
    """A command ran past `HANG_S`."""


def _alarm(signum, frame):
    raise HangError()


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    """(exit code, stdout, stderr) of `vtable ARGV` run in this process, `HANG_S` at most."""
    import contextlib
    import io
    import signal

    from vtable.cli import main

    out, err = io.StringIO(), io.StringIO()
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(HANG_S)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(argv)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    return code, out.getvalue(), err.getvalue()


def vtable_exe() -> list[str]:
    """The command that runs vtable in a process of its own, as a user's shell does."""
    import sys

    exe = shutil.which("vtable")
    return [exe] if exe else [sys.executable, "-m", "vtable.cli"]


def python_output(code: str, timeout: float = 300) -> str:
    """What `code` prints, run by this Python in a process of its own (asserted to exit 0,
    its stderr's tail shown when it does not)."""
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=timeout)
    assert r.returncode == 0, r.stderr[-2000:]
    return r.stdout


def nonlinear_controllers(vt, air_ratio: float = 0.0, friction: float = 0.0) -> list:
    """The multibody table `vt`'s controllers with appendix C valves on H1-H3: the stages
    of the valve_flow_nonlinearity (orifice flow from the table's supply pressure) and
    flow_saturation (the rated flow) effects, optionally oil_column_air's (`air_ratio`)
    and actuator_friction's (`friction`, N per actuator), after the table's own stages;
    linear loops on V1-V4, passive stabilizers."""
    from vtable.controllers import HydraulicServo, PassiveStabilizers, ServoController
    from vtable.effects.actuator_friction import FRICTION, V_EPS
    from vtable.effects.flow_saturation import FLOW_CAP
    from vtable.effects.oil_column_air import AIR
    from vtable.effects.valve_flow_nonlinearity import ORIFICE
    from vtable.hydraulics.table_stages import table_stages

    ps = vt.table.geometry.supply_pressure
    stages = [*table_stages(vt), (ORIFICE, {"supply_pressure": ps}),
              (FLOW_CAP, {"max_flow": vt.table.rated_flow("H1")})]
    if air_ratio:
        stages.append((AIR, {"air_ratio": air_ratio, "mean_pressure": ps}))
    if friction:
        stages.append((FRICTION, {"friction": friction, "v_eps": V_EPS}))
    return [HydraulicServo(vt, stages=tuple(stages)), ServoController(vt, groups=("vertical",))] \
        + ([PassiveStabilizers(vt)] if vt.stabilizers.pairs else [])
