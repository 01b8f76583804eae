"""`conftest.made_once`: a fixture's value made by one pytest-xdist worker and read back by
the others, under a lock that a process `make` forks does not keep."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

from conftest import made_once, shared_temp


def test_the_value_is_made_once_and_the_lock_is_free_though_make_forked(tmp_path_factory):
    """`make` forks a child that outlives it, as a diagnosis's Dask workers do (they
    inherit the lock's file): once `made_once` returns, another process takes the lock at
    once; asked again, the value is read back, `make` not called."""
    calls, children = [], []

    def make(folder):
        calls.append(folder)
        (folder / "made.txt").write_text("42")
        pid = os.fork()
        if pid == 0:  # the child holds every file its parent had open, then sleeps
            time.sleep(60)
            os._exit(0)
        children.append(pid)
        return {"n": 42, "file": str(folder / "made.txt")}

    try:
        first = made_once(tmp_path_factory, "probe", make)
        lock = shared_temp(tmp_path_factory) / "made-once-probe.lock"
        taken = subprocess.run(
            [sys.executable, "-c", "import fcntl, sys\nf = open(sys.argv[1], 'w')\n"
             "fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)\nprint('taken')", str(lock)],
            capture_output=True, text=True, timeout=60)
        assert taken.stdout.strip() == "taken", taken.stderr[-500:]
        again = made_once(tmp_path_factory, "probe", make)
    finally:
        for pid in children:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
    assert len(calls) == 1
    assert first == again == {"n": 42, "file": first["file"]}
    assert open(again["file"]).read() == "42"
