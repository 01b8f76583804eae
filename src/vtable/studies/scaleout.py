"""Studies at scale: a grid of points (specimen heights × records, ...) evaluated through
the analytical models or the virtual table on a Dask cluster, each result written to an
on-disk store as it completes, so an interrupted study resumes where it stopped.

The store is a folder: ``study.json`` (the study's definition: function and points) and
``points/KEY.json`` per finished point, written to a temporary file and renamed, so a
point file is either complete or absent. Only the client writes; workers only compute.
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from importlib import import_module
from pathlib import Path
from typing import Any

import numpy as np
from dask.distributed import Client, LocalCluster, as_completed

from vtable import units
from vtable.errors import VtableError
from vtable.jsonable import jsonable
from vtable.signals import COMMAND_DT, Command
from vtable.signals.processing import process_record
from vtable.signals.records import load_record
from vtable.signals.spectra import effective_motion, response_spectrum
from vtable.sim.experiment import load_specimen
from vtable.sim.run import simulate, standard_physics
from vtable.studies.interaction import assess

FORMAT = "vtable-study/1"


@dataclass(frozen=True)
class Study:
    """`function` ("module:name", importable on the workers) applied to each point's
    keyword arguments; `points` maps a key (used as a file name) to those arguments."""

    function: str
    points: Mapping[str, Mapping[str, Any]]

    def to_dict(self) -> dict[str, Any]:
        return {"format": FORMAT, "function": self.function,
                "points": {k: dict(v) for k, v in self.points.items()}}


class Store:
    """The on-disk results of one study (see the module docstring)."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)
        self.points_dir = self.root / "points"

    def open(self, study: Study) -> None:
        """Create the store for `study`, or check that an existing one holds the same
        study; remove temporary files an interrupted writer left behind."""
        spec = self.root / "study.json"
        want = study.to_dict()
        if spec.exists():
            try:
                have = json.loads(spec.read_text())
            except json.JSONDecodeError as e:
                raise VtableError(f"{spec}: not a study definition ({e})") from None
            if have != json.loads(json.dumps(want)):
                raise VtableError(f"{self.root} holds a different study (function or points "
                                  "differ); use another store folder")
        else:
            self.points_dir.mkdir(parents=True, exist_ok=True)
            _atomic_write(spec, json.dumps(want, indent=1))
        self.points_dir.mkdir(parents=True, exist_ok=True)
        for tmp in self.points_dir.glob("*.tmp"):
            tmp.unlink()

    def done(self) -> set[str]:
        return {p.stem for p in self.points_dir.glob("*.json")}

    def write(self, key: str, result: Mapping[str, Any]) -> None:
        _atomic_write(self.points_dir / f"{key}.json", json.dumps(jsonable(result)))

    def load(self) -> dict[str, dict[str, Any]]:
        """Every finished point's result, by key."""
        out = {}
        for p in sorted(self.points_dir.glob("*.json")):
            try:
                out[p.stem] = json.loads(p.read_text())
            except json.JSONDecodeError as e:
                raise VtableError(f"{p}: unreadable point result ({e})") from None
        return out


def _atomic_write(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def resolve(function: str) -> Callable[..., Mapping[str, Any]]:
    mod, _, name = function.partition(":")
    try:
        return getattr(import_module(mod), name)
    except (ImportError, AttributeError):
        raise VtableError(f"study function {function!r} is not importable") from None


def _call(function: str, kwargs: Mapping[str, Any]) -> Mapping[str, Any]:
    return resolve(function)(**kwargs)


def run_study(study: Study, store: str | Path, *, scheduler: str | None = None,
              n_workers: int = 2, progress: Callable[[str], None] | None = None
              ) -> dict[str, dict[str, Any]]:
    """Evaluate the study's unfinished points on Dask (a local cluster of `n_workers`
    single-threaded processes, or the scheduler at `scheduler`), storing each result as
    it completes; return every point's result."""
    resolve(study.function)  # fail here, not on the workers
    st = Store(store)
    st.open(study)
    todo = [k for k in study.points if k not in st.done()]
    say = progress or (lambda s: print(s, file=sys.stderr, flush=True))
    n_all, n_done = len(study.points), len(study.points) - len(todo)
    say(f"study: {n_all} points, {n_done} already in {st.root}, {len(todo)} to run")
    if todo:
        cluster = None
        if scheduler:
            client = Client(scheduler)
        else:
            cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        try:
            t0 = time.perf_counter()
            futures = {client.submit(_call, study.function, dict(study.points[k]), pure=False,
                                     key=f"vtable-point-{k}"): k for k in todo}
            for fut in as_completed(futures):
                k = futures[fut]
                st.write(k, fut.result())
                n_done += 1
                say(f"[{n_done}/{n_all}] {k} ({time.perf_counter() - t0:.1f} s)")
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    return st.load()


# ---- the points -------------------------------------------------------------------------
def _command(record: str, duration: float | None):
    cmd = process_record(load_record(record))
    if duration is not None:
        n = min(len(cmd.displacement), round(duration / cmd.dt) + 1)
        cmd = replace(cmd, displacement=cmd.displacement[:n], acceleration=cmd.acceleration[:n])
    return cmd


def _specimen(specimen: str, height_in: float | None):
    spec = load_specimen(specimen)
    return spec if height_in is None else replace(spec, height=units.to_si(height_in, "in"))


def virtual_table_point(record: str, height_in: float | None = None,
                        specimen: str = "sdof_frame", duration: float | None = 4.0,
                        periods: tuple[float, ...] = (0.1, 0.2, 0.35, 0.5, 1.0)
                        ) -> dict[str, Any]:
    """One virtual-table run: the specimen (its height changed to `height_in`) under the
    §9.2-processed `record` (first `duration` s): peaks of the table channels and the
    effective-motion spectrum (x_t + hθ, 5 %) over the command's."""
    spec = _specimen(specimen, height_in)
    cmd = _command(record, duration)
    t = np.arange(0.0, cmd.time[-1] + 1e-12, COMMAND_DT)
    run = simulate(standard_physics(spec), Command(
        cmd.name, t, np.interp(t, cmd.time, cmd.displacement),
        {"kind": "earthquake", "record": record}))
    eff = effective_motion(run, spec.height)
    s_eff = response_spectrum(eff, run.dt, periods).psa
    s_cmd = response_spectrum(cmd.acceleration, cmd.dt, periods).psa
    peaks = {k: float(np.max(np.abs(run.channels[k])))
             for k in ("avg_hdisp", "avg_hacc", "pitch_acc", "pitch_disp")}
    return {"height_in": height_in, "record": record, "peaks_si": peaks,
            "periods_s": list(periods), "psa_ratio": (s_eff / s_cmd).tolist()}


def analytic_point(record: str, height_in: float | None = None, specimen: str = "sdof_frame",
                   duration: float | None = None) -> dict[str, Any]:
    """One analytical assessment (§9.3-9.9): coupled modes and PSV at the specimen period
    through the five models."""
    spec = _specimen(specimen, height_in)
    cmd = _command(record, duration)
    a = assess(spec, cmd.acceleration, cmd.dt, record, periods=[1 / spec.frequency])
    return {"height_in": height_in, "record": record,
            "modes": {k: list(v) for k, v in a.modes.items()},
            "psv_at_specimen": a.psv_at_specimen, "rocking_share": a.rocking_share}


FUNCTIONS = {"virtual": "vtable.studies.scaleout:virtual_table_point",
             "analytic": "vtable.studies.scaleout:analytic_point"}


def height_record_study(heights_in, records, model: str = "virtual",
                        **common: Any) -> Study:
    """The grid heights × records through `model` (virtual or analytic)."""
    if model not in FUNCTIONS:
        raise VtableError(f"study model must be virtual or analytic, got {model!r}")
    for r in records:  # a bad record fails here in one line, before any cluster starts
        load_record(str(r))
    points = {}
    records = [str(Path(r).resolve()) if Path(r).is_file() else str(r) for r in records]
    for r_i, rec in enumerate(records):
        for h in heights_in:
            points[f"r{r_i}-h{float(h):g}"] = {"record": str(rec), "height_in": float(h),
                                               **common}
    return Study(FUNCTIONS[model], points)
