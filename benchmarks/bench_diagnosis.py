"""Speed of a full-catalog diagnosis (issues 12 and 31), wall and CPU time (CPU = this
process and its Dask worker processes, which fit the candidates and are started anew for
each figure, their start counted in its wall time):

1. a three-run, 44-second campaign at 200 Hz (two 11 s random runs and the §9.2 El Centro
   run; SDOF frame with pitch flexibility hidden; 1 % noise):
   a. made on the virtual table in-process (`simulate`), the kernel compile measured
      separately;
   b. made with `vtable simulate` as the README shows (three runs written, read back);
2. three real-size runs (165 s + 165 s random, 45 s El Centro at its own time scale;
   200 Hz, ~75 000 samples in all) made by the independent truth simulator (tests/truth)
   with a perturbed declaration and actuator friction hidden;
3. the README's campaign (`vtable simulate`: random 0.1 and 0.25 in, El Centro at 2 in;
   3 kip of friction hidden, 1 % noise) diagnosed by `vtable diagnose` as a user runs it
   (`vtable.warm`: the environment's first command starts its warm process, which answers
   the later ones), timed from outside: the first command; warm (the median of 5 runs:
   this machine's speed varies by a fifth), and warm with one process per command
   (``VTABLE_WARM=0``, each command importing the libraries itself, as before the warm
   process); cold (numba's cache empty: a new environment, so a new warm process); and
   warm with the HTML report the README's command draws (no target: what its user waits
   for). vtable's modules are compiled to bytecode first, as
   the README's `pip install .` does: an editable install under PYTHONDONTWRITEBYTECODE
   (this machine's environment sets it) never writes it, and each run compiled ~200
   modules again (~0.13 s); `--no-bytecode` leaves it as it is.

Targets (issue 31): 1a <= 2 s, 1b <= 3 s, 2 <= 10 s, 3 <= 5 s warm and <= 20 s cold.

    python benchmarks/bench_diagnosis.py [--fs 200] [--only 1a,1b,2,3] [--repeat 5]
                                         [--no-bytecode]

Each figure is preceded and the run ended by a yardstick: the same fixed work (a pure-Python
loop on one core and on both at once, a numpy SVD) timed, so that a slow spell of the
machine (a shared host's speed drifts by half within minutes here: the README figure took
4.9 s and 8.1 s ten minutes apart, its CPU seconds 8.2 and 13.0 for the same work) is
told from a slower diagnosis: compare figures taken at the same yardstick.

`--fs` samples campaign 1a at another rate (256, 1000, ...): faster runs are analysed at
200 Hz after anti-alias resampling, so the diagnosis should cost about the same."""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from vtable.diagnose import workers
from vtable.diagnose.engine import Diagnoser
from vtable.models.physics import Physics, nominal_open_loop
from vtable.params import presets
from vtable.runs import read_run
from vtable.signals import make_command
from vtable.sim import simulate

TESTS = Path(__file__).resolve().parents[1] / "tests"


def _cpu() -> float:
    """CPU seconds of this process and of its children that have ended."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _loop(_: object = None) -> float:
    """A fixed pure-Python loop's wall time (s)."""
    t = time.perf_counter()
    s = 0
    for i in range(2_000_000):
        s += i * i
    return time.perf_counter() - t


def yardstick() -> str:
    """This machine's speed now: a fixed pure-Python loop on one core and on both at once
    (the slower of the two: a shared host's second core is not always as fast), and a
    fixed numpy SVD (one thread), their wall times (the module docstring)."""
    import multiprocessing

    one = _loop()
    with multiprocessing.get_context("fork").Pool(2) as pool:
        two = max(pool.map(_loop, [0, 1]))
    x = np.random.default_rng(0).random((300, 300))
    with threadpool_limits(1):
        t = time.perf_counter()
        for _ in range(10):
            np.linalg.svd(x)
        svd = time.perf_counter() - t
    return (f"  (yardstick: python loop {one * 1e3:.0f} ms, on both cores at once "
            f"{two * 1e3:.0f} ms; svd {svd * 1e3:.0f} ms)")


class Clock:
    """Wall and CPU seconds since construction (CPU: this process and its ended children;
    the worker processes count once `workers.shutdown()` has ended them)."""

    def __init__(self) -> None:
        self.w, self.c = time.perf_counter(), _cpu()

    def __str__(self) -> str:
        return f"wall {time.perf_counter() - self.w:.1f} s, CPU {_cpu() - self.c:.1f} s"

    @property
    def wall(self) -> float:
        return time.perf_counter() - self.w

    @property
    def cpu(self) -> float:
        return _cpu() - self.c


def diagnose(label: str, runs, target: float, compile_first: bool = False) -> None:
    n = sum(len(r.time) for r in runs)
    secs = sum(r.duration for r in runs)
    if compile_first:
        k = Clock()
        Diagnoser(runs).score(Physics(nominal_open_loop(), presets.specimen("sdof_frame")))
        print(f"  kernel load/compile (this process): {k}")
    workers.shutdown()  # each figure starts its worker processes, as a new `vtable diagnose`
    c = Clock()  # what a user waits for: the campaign prepared, the workers started, the loop
    d = Diagnoser(runs)
    result = d.diagnose()
    wall = c.wall
    workers.shutdown()  # the workers' CPU is counted once they have ended
    ok = "within" if wall <= target else "OVER"
    print(f"  {label}: {len(runs)} runs, {secs:.1f} s, {n} samples; full-catalog diagnosis "
          f"({len(d.catalog)} effects, {len(result.rounds)} rounds): wall {wall:.1f} s, "
          f"CPU {str(c).split('CPU ')[1]} with the workers' ({ok} the target {target:g} s)")
    print(f"  found {result.final_effects or 'nothing'}; verdict: {result.verdict}")


def campaign_virtual(fs: float) -> None:
    print(f"1a. virtual-table campaign at {fs:g} Hz (pitch_flexibility hidden)")
    cmds = [make_command("random", duration=11.0, band=(0.0, 25.0), peak_in=0.05, seed=1),
            make_command("random", duration=11.0, band=(0.0, 25.0), peak_in=0.15, seed=2),
            make_command("earthquake", peak_in=4.0)]
    truth = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                    {"pitch_flexibility": {}})
    c = Clock()
    runs = [simulate(truth, cmd, noise=0.01, seed=i, name=f"run{i}", rate=fs)
            for i, cmd in enumerate(cmds)]
    print(f"  simulated: {c}")
    diagnose("virtual table", runs, 2.0, compile_first=True)


def campaign_cli(folder: Path) -> None:
    print("1b. campaign made with `vtable simulate` (README), SDOF frame, standard table")
    exe = [sys.executable, "-m", "vtable"]
    calls = [["--command", "random", "--band", "0", "25", "--peak", "0.05", "--duration", "11",
              "--seed", "1"],
             ["--command", "random", "--band", "0", "25", "--peak", "0.15", "--duration", "11",
              "--seed", "2"],
             ["--command", "earthquake", "--peak", "4"]]
    c = Clock()
    paths = []
    for i, args in enumerate(calls):
        stem = folder / f"cli_run{i}"
        subprocess.run([*exe, "simulate", "--specimen", "sdof_frame", *args, "--out",
                        str(stem)], check=True, stdout=subprocess.DEVNULL)
        paths.append(stem.with_suffix(".toml"))
    print(f"  simulated (3 x vtable simulate, wall only): {c.wall:.1f} s")
    diagnose("vtable simulate", [read_run(p) for p in paths], 3.0)


def campaign_real_size(folder: Path) -> None:
    print("2. real-size runs from the truth simulator (friction 3 kip hidden, declaration "
          "perturbed)")
    sys.path.insert(0, str(TESTS))
    import truth

    spec = truth.sdof(68.0, 219.0, 2.87, 0.02)
    decl = truth.perturb(spec, seed=5, frequency=0.03, damping=1.5, weight=0.05)
    table = truth.eerc_table(effects={"actuator_friction": {"friction": 3.0}})
    cmds = [("random_0", truth.random_command(165.0, (0, 25), peak_in=0.1, seed=1)),
            ("random_1", truth.random_command(165.0, (0, 25), peak_in=0.5, seed=2)),
            ("earthquake", truth.earthquake_command("elcentro", peak_in=3.0, time_scale=1.0))]
    c = Clock()
    paths = []
    for k, (name, cmd) in enumerate(cmds):
        res = truth.simulate(table, spec, cmd, fs=200.0)
        paths.append(truth.write_run(folder / name, res, decl, noise=0.02, seed=100 + k)[0])
    print(f"  simulated: {c}")
    diagnose("truth, real size", [read_run(p) for p in paths], 10.0)


README_CALLS = (("random_010", ["--command", "random", "--band", "0", "25", "--peak", "0.1",
                                "--duration", "11", "--seed", "1"]),
                ("random_025", ["--command", "random", "--band", "0", "25", "--peak", "0.25",
                                 "--duration", "11", "--seed", "2"]),
                ("elcentro", ["--command", "earthquake", "--record", "elcentro", "--peak", "2",
                              "--seed", "3"]))


def compile_bytecode() -> None:
    """vtable's modules (its package, `vtable.controllers`, `vtable.viz`) compiled to
    bytecode where they live, as `pip install .` compiles them (figure 3)."""
    import compileall
    import importlib.util

    for name in ("vtable", "vtable.controllers", "vtable.viz"):
        for folder in importlib.util.find_spec(name).submodule_search_locations or ():
            compileall.compile_dir(folder, quiet=1)


def campaign_readme(folder: Path, repeat: int = 5, bytecode: bool = True) -> None:
    """3. The README's campaign: three `vtable simulate` runs (random 0.1 and 0.25 in,
    El Centro at 2 in) with 3 kip of actuator friction hidden and 1 % noise, diagnosed by
    `vtable diagnose` as a user runs it: a process of its own, warm (numba's cache holds
    the kernels) and cold (an empty cache: every kernel compiled); warm, the median of
    `repeat` runs. `bytecode`: whether vtable's bytecode was compiled first (main)."""
    how = "its bytecode compiled, as pip install . does" if bytecode else "bytecode as installed"
    print("3. the README's campaign (vtable simulate: random 0.1 and 0.25 in, El Centro 2 in; "
          f"friction 3 kip hidden, 1 % noise), `vtable diagnose` as a user runs it ({how})")
    exe = [sys.executable, "-m", "vtable"]
    paths = []
    for name, args in README_CALLS:
        stem = folder / f"readme_{name}"
        subprocess.run([*exe, "simulate", "--specimen", "sdof_frame", *args, "--effect",
                        "actuator_friction:friction=3", "--noise", "0.01", "--out", str(stem)],
                       check=True, stdout=subprocess.DEVNULL)
        paths.append(str(stem.with_suffix(".toml")))
    import os

    def stop_warm(env: dict) -> None:  # the warm process the commands of `env` use
        subprocess.run([*exe, "warm", "--stop"], env=env, check=True,
                       stdout=subprocess.DEVNULL)
        time.sleep(1.0)

    report = ["--report", str(folder / "d.html")]  # the README's command draws its report
    stop_warm(dict(os.environ))  # the first command below starts this environment's
    for label, cache, extra, times, alone in (
            ("the environment's first command (it starts the warm process)", None, [], 1,
             False),
            ("warm", None, [], repeat, False),
            ("warm, one process per command (VTABLE_WARM=0, as before the warm process)",
             None, [], repeat, True),
            ("cold", folder / "empty-numba-cache", [], 1, False),
            ("warm, with the HTML report (the README's command)", None, report, 1, False)):
        env = dict(os.environ)
        if cache is not None:
            env["NUMBA_CACHE_DIR"] = str(cache)
        if alone:
            env["VTABLE_WARM"] = "0"
        walls, cpus = [], []
        for _ in range(times):  # this machine's speed varies by a fifth: the median of
            c = Clock()         # several runs, with their range
            out = subprocess.run([*exe, "diagnose", *paths, "--json", str(folder / "d.json"),
                                  *extra], env=env, capture_output=True, text=True)
            walls.append(c.wall)
            cpus.append(c.cpu)
            if out.returncode != 0:
                break
        import json

        if cache is not None:
            stop_warm(env)  # the cold run's warm process, of an environment now gone
        if out.returncode != 0:
            print(f"  {label}: vtable diagnose failed: {out.stderr.strip()[-300:]}")
            continue
        d = json.loads((folder / "d.json").read_text())
        wall, cpu = float(np.median(walls)), float(np.median(cpus))
        spread = f" (median of {times}: {min(walls):.1f}-{max(walls):.1f} s)" if times > 1 else ""
        target = {"warm": 5.0, "cold": 20.0}.get(label)
        judged = "no target" if target is None else \
            f"{'within' if wall <= target else 'OVER'} the target {target:g} s"
        used = (f"CPU {cpu:.1f} s (the process and its workers; {judged})" if alone else
                f"{judged}; its CPU is the warm process's, not counted")
        print(f"  {label}: wall {wall:.1f} s{spread}, {used}; found "
              f"{d.get('final_effects')}, final {d.get('final_error', float('nan')):.2%}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--fs", type=float, default=200.0, help="campaign 1a's sample rate (Hz)")
    ap.add_argument("--only", default="1a,1b,2,3", help="which figures (1a, 1b, 2, 3)")
    ap.add_argument("--repeat", type=int, default=5,
                    help="figure 3 warm: the median of this many runs")
    ap.add_argument("--no-bytecode", action="store_true",
                    help="figure 3: vtable's bytecode as the installation left it")
    a = ap.parse_args()
    only = {s.strip() for s in a.only.split(",")}
    with tempfile.TemporaryDirectory() as tmp:
        if "1a" in only:
            print(yardstick())
            campaign_virtual(a.fs)
        if "1b" in only:
            print(yardstick())
            campaign_cli(Path(tmp))
        if "2" in only:
            print(yardstick())
            campaign_real_size(Path(tmp))
        if "3" in only:
            if not a.no_bytecode:
                compile_bytecode()
            print(yardstick())
            campaign_readme(Path(tmp), max(1, a.repeat), not a.no_bytecode)
        print(yardstick())


if __name__ == "__main__":
    main()
