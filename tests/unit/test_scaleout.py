"""Dask scale-out: a 2-worker local study of the virtual table over 8 heights x 3 records,
killed halfway and resumed, equals an uninterrupted run."""

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from vtable.errors import VtableError
from vtable.studies.scaleout import Store, Study, height_record_study

HEIGHTS = [100, 140, 180, 219, 260, 300, 350, 400]


def _write_at2(path, acc_g, dt, title):
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD", title,
             "ACCELERATION TIME SERIES IN UNITS OF G",
             f"NPTS=  {len(acc_g)}, DT=   {dt:.4f} SEC"]
    lines += ["  ".join(f"{v:.7E}" for v in acc_g[i:i + 5]) for i in range(0, len(acc_g), 5)]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    d = tmp_path_factory.mktemp("records")
    rng = np.random.default_rng(7)
    out = ["elcentro"]
    for i, f0 in enumerate((1.5, 4.0)):
        t = np.arange(0, 12, 0.01)
        acc = (0.2 * np.exp(-((t - 4) / 3) ** 2) * np.sin(2 * np.pi * f0 * t)
               + 0.02 * rng.standard_normal(len(t)))
        p = d / f"synthetic{i}.AT2"
        _write_at2(p, acc, 0.01, f"synthetic record {i}, {f0} Hz")
        out.append(str(p))
    return out


def _cli(store, records):
    return [sys.executable, "-m", "vtable.cli", "study", "--store", str(store),
            "--records", *records, "--duration", "3", "--workers", "2",
            "--heights", *map(str, HEIGHTS)]


def test_killed_study_resumes_to_the_uninterrupted_result(tmp_path, records):
    full, broken = tmp_path / "full", tmp_path / "broken"
    done = subprocess.run(_cli(full, records), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "[24/24]" in done.stderr
    reference = Store(full).load()
    assert len(reference) == 24

    proc = subprocess.Popen(_cli(broken, records), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    points = broken / "points"
    t0 = time.time()
    while time.time() - t0 < 300:
        if points.is_dir() and len(list(points.glob("*.json"))) >= 12:
            break
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)  # the client and its workers, mid-study
    proc.wait()
    before = {p.name: (p.stat().st_mtime_ns, p.read_text()) for p in points.glob("*.json")}
    assert 12 <= len(before) < 24, len(before)  # halfway

    resumed = subprocess.run(_cli(broken, records), capture_output=True, text=True,
                             timeout=600)
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    assert f"{len(before)} already in" in resumed.stderr
    assert f"{24 - len(before)} to run" in resumed.stderr
    for name, (mtime, text) in before.items():  # finished points were not recomputed
        p = points / name
        assert p.stat().st_mtime_ns == mtime and p.read_text() == text
    assert Store(broken).load() == reference
    assert not list(points.glob("*.tmp"))
    # the study varied what it should: pitch grows with height under one record
    pitch = [reference[f"r0-h{h}"]["peaks_si"]["pitch_disp"] for h in HEIGHTS]
    assert pitch[-1] > 2 * pitch[0]


def test_store_refuses_another_study(tmp_path):
    s1 = height_record_study([100, 200], ["elcentro"], "analytic")
    Store(tmp_path).open(s1)
    Store(tmp_path).open(s1)  # the same study reopens
    with pytest.raises(VtableError, match="different study"):
        Store(tmp_path).open(height_record_study([100, 300], ["elcentro"], "analytic"))
    with pytest.raises(VtableError, match="not importable"):
        from vtable.studies.scaleout import run_study
        run_study(Study("vtable.nowhere:f", {"a": {}}), tmp_path / "x")
    (tmp_path / "points" / "r0-h100.json").write_text("{broken")
    with pytest.raises(VtableError, match=r"r0-h100\.json: unreadable"):
        Store(tmp_path).load()
    assert json.loads((tmp_path / "study.json").read_text())["points"]["r0-h200"] == {
        "record": "elcentro", "height_in": 200.0}


def test_study_on_a_scheduler_address(tmp_path):
    from dask.distributed import LocalCluster

    from vtable.studies.scaleout import run_study

    lines = []
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster:
        out = run_study(height_record_study([219.0, 300.0], ["elcentro"], "analytic"),
                        tmp_path, scheduler=cluster.scheduler_address, progress=lines.append)
    assert out["r0-h219"]["modes"]["hybrid"][0] == pytest.approx(2.54, abs=0.01)
    assert out["r0-h300"]["modes"]["hybrid"][0] < out["r0-h219"]["modes"]["hybrid"][0]
    assert lines[0].startswith("study: 2 points, 0 already") and lines[-1].startswith("[2/2]")
