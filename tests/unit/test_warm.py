"""The warm process (`vtable.warm`): `vtable diagnose` answered by a process that has
its libraries loaded, with what the command prints, writes and exits with unchanged;
Ctrl-C, a caller killed outright, a module changed on disk, a bad setting."""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
from conftest import run_cli

from vtable.diagnose.pool import WORKERS
from vtable.warm import holder

DIAGNOSE = [sys.executable, "-m", "vtable", "diagnose"]


@pytest.fixture
def warm(request):
    """The environment of a caller whose warm processes live in a folder of this test's
    (short: a socket's path is at most ~100 bytes), and that folder; every warm process
    started there is stopped after the test."""
    tmp = Path(tempfile.mkdtemp(prefix="vw", dir="/tmp"))
    env = {**os.environ, "VTABLE_WARM": "1", "TMPDIR": str(tmp)}
    env.pop("PYTEST_CURRENT_TEST", None)  # changes between a test's phases
    yield env, tmp
    for lock in tmp.glob("vtable-*/*.sock.lock"):
        pid = holder(Path(str(lock)[:-len(".lock")]))  # a live one only: no pid reused
        with contextlib.suppress(ProcessLookupError):
            if pid is not None:
                os.kill(pid, signal.SIGTERM)
    shutil.rmtree(tmp, ignore_errors=True)


def _log(tmp: Path) -> str:
    logs = list(tmp.glob("vtable-*/*.log"))
    return "".join(p.read_text() for p in logs)


def _logged(tmp: Path, text: str, times: int = 1, within: float = 20.0) -> bool:
    """Whether `text` is in the log `times` times within `within` seconds (a child's end is
    logged once the warm process has reaped it, after its caller has exited)."""
    end = time.monotonic() + within
    while _log(tmp).count(text) < times:
        if time.monotonic() > end:
            return False
        time.sleep(0.05)
    return True


def _servers(tmp: Path) -> list[str]:
    """The pids of the warm processes that have listened, in order."""
    return re.findall(r"\[(\d+)\] listening", _log(tmp))


def _children(tmp: Path) -> list[int]:
    return [int(p) for p in re.findall(r"\] pid (\d+): vtable", _log(tmp))]


def _gone(pid: int, within: float) -> bool:
    end = time.monotonic() + within
    while time.monotonic() < end:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.05)
    return False


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """Three runs of the SDOF frame on the virtual table with 3 kip of friction, 1 % noise,
    as the README makes them (shorter)."""
    folder = tmp_path_factory.mktemp("warm_campaign")
    runs = [("small", ["--command", "random", "--band", "0", "20", "--peak", "0.1",
                       "--duration", "8", "--seed", "1"]),
            ("large", ["--command", "random", "--band", "0", "20", "--peak", "0.25",
                       "--duration", "8", "--seed", "2"])]
    for name, args in runs:
        code, _, err = run_cli(["simulate", "--specimen", "sdof_frame", *args, "--effect",
                                "actuator_friction:friction=3", "--noise", "0.01",
                                "--out", str(folder / name)])
        assert code == 0, err
    return folder, [str(folder / f"{name}.toml") for name, _ in runs]


def test_a_command_is_answered_by_one_warm_process_as_it_would_be_alone(warm, tmp_path):
    env, tmp = warm
    alone = {**env, "VTABLE_WARM": "0"}
    for argv in (["nothere.toml"], ["--help"]):
        want = subprocess.run([*DIAGNOSE, *argv], env=alone, cwd=tmp_path, capture_output=True,
                              text=True, timeout=120)
        for _ in range(2):
            got = subprocess.run([*DIAGNOSE, *argv], env=env, cwd=tmp_path,
                                 capture_output=True, text=True, timeout=120)
            assert (got.returncode, got.stdout, got.stderr) == \
                (want.returncode, want.stdout, want.stderr)
    assert want.returncode == 0 and "usage: vtable diagnose" in want.stdout
    assert len(_servers(tmp)) == 1  # started by the first, used by the other three
    log = _log(tmp)
    assert f"vtable diagnose nothere.toml (in {tmp_path})" in log
    assert _logged(tmp, ": exit 2", 2) and _logged(tmp, ": exit 0", 2)


def test_a_diagnosis_through_the_warm_process_is_the_same(warm, campaign):
    """Byte for byte the JSON of one in a process of its own, the first time and after the
    warm process has loaded the kernels the first one built and parsed the run files it
    read (once each: the next command took that parse, and had none to report)."""
    env, tmp = warm
    folder, files = campaign
    out = {}
    for k, how in enumerate(("0", "1", "1")):
        path = folder / f"d{k}.json"
        r = subprocess.run([*DIAGNOSE, *files, "--json", str(path)],
                           env={**env, "VTABLE_WARM": how}, capture_output=True, text=True,
                           timeout=300)
        assert r.returncode == 0, r.stderr[-2000:]
        out[k] = path.read_bytes()
        if k == 1:  # the kernel sets the first diagnosis built, loaded before the next
            assert _logged(tmp, "kernel sets loaded", within=60)
    assert out[1] == out[0] and out[2] == out[0]
    assert len(_servers(tmp)) == 1 and len(_children(tmp)) == 2
    n = int(re.search(r"(\d+) kernel sets loaded", _log(tmp)).group(1))
    assert n >= 3  # the start, pitch and friction at least
    assert _logged(tmp, "kernel sets loaded", times=2, within=60)  # the second's lessons
    for f in files:
        csv = str(Path(f).with_suffix(".csv").resolve())
        assert _log(tmp).count(f"{csv}: parsed") == 1, _log(tmp)[-2000:]


def _started(env: dict, files: list[str], ignore: tuple = ()
             ) -> tuple[subprocess.Popen, list[str]]:
    """A warm diagnosis once its first round has begun, and what it has said so far; its
    caller ignores the signals `ignore` (as `nohup` does SIGHUP). The caller has a process
    group of its own, whose parent (this test) is in another of the same session: never
    an orphaned group, where the kernel would drop the Ctrl-Z it sends itself (a suite
    run under `setsid`, or by a `nohup` whose shell has ended)."""
    def dispositions() -> None:
        # whatever the test run's own (CI under nohup, a shell's background job)
        for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM, signal.SIGTSTP):
            signal.signal(s, signal.SIG_IGN if s in ignore else signal.SIG_DFL)

    p = subprocess.Popen([*DIAGNOSE, *files], env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, preexec_fn=dispositions,
                         process_group=0)
    seen = []
    for line in p.stderr:
        seen.append(line)
        if "round 1" in line:
            return p, seen
    raise AssertionError("".join(seen)[-2000:])


def test_ctrl_c_in_the_caller_interrupts_the_command(warm, campaign):
    env, tmp = warm
    p, seen = _started(env, campaign[1])
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    lines = (("".join(seen) + err).strip().splitlines())
    assert p.returncode == 130, err
    assert lines[-1].startswith("vtable: interrupted") and "Traceback" not in err
    child = _children(tmp)[-1]
    assert _gone(child, 10) and _logged(tmp, f"pid {child}: exit 130")


def _stat(path: Path) -> list[str]:
    """The fields of a /proc/<pid>/stat after the command's name: its state first, then
    its parent, its process group, ..."""
    return path.read_text().rsplit(")", 1)[1].split()


def _state(pid: int, state: str, within: float = 10.0) -> bool:
    """Whether process `pid` is in `state` ("T": stopped) within `within` seconds."""
    end = time.monotonic() + within
    while time.monotonic() < end:
        with contextlib.suppress(OSError):
            if _stat(Path(f"/proc/{pid}/stat"))[0] == state:
                return True
        time.sleep(0.02)
    return False


def _group(pgid: int) -> list[int]:
    """The processes of process group `pgid`."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, IndexError, ValueError):
            if int(_stat(stat)[2]) == pgid:
                out.append(int(stat.parent.name))
    return out


def test_a_caller_killed_outright_stops_its_command(warm, campaign):
    env, tmp = warm
    p, _ = _started(env, campaign[1])
    p.kill()  # its streams kept open, as a terminal would keep them
    p.wait(timeout=10)
    child = _children(tmp)[-1]
    assert _gone(child, 20), _log(tmp)
    assert _logged(tmp, f"pid {child}: exit 130")
    p.stdout.close()
    p.stderr.close()


def test_a_module_changed_on_disk_is_a_new_warm_process(warm, tmp_path):
    """A module the warm process has loaded (here the caller's sitecustomize) changed: the
    next command is answered by a new one, which loads the new text."""
    env, tmp = warm
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text("")
    env = {**env, "PYTHONPATH": os.pathsep.join(filter(None, [str(site),
                                                             env.get("PYTHONPATH")]))}

    def diagnose_help() -> None:
        r = subprocess.run([*DIAGNOSE, "--help"], env=env, capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 0 and "usage: vtable diagnose" in r.stdout, r.stderr

    diagnose_help()
    diagnose_help()
    assert len(_servers(tmp)) == 1
    (site / "sitecustomize.py").write_text("import os  # changed\n")
    diagnose_help()
    assert len(_servers(tmp)) == 2
    assert f"{site / 'sitecustomize.py'} changed: no more commands" in _log(tmp)
    assert _logged(tmp, ": exit 0", 3)


def test_a_bad_setting_is_one_line():
    r = subprocess.run([*DIAGNOSE, "x.toml"], env={**os.environ, "VTABLE_WARM": "yes"},
                       capture_output=True, text=True, timeout=60)
    assert (r.returncode, r.stdout, r.stderr) == (
        2, "", "vtable: error: VTABLE_WARM must be 0 or 1, not 'yes'\n")


def test_vtable_warm_tells_and_stops_the_warm_process(warm):
    env, tmp = warm

    def vtable_warm(*args: str) -> dict:
        r = subprocess.run([sys.executable, "-m", "vtable", "warm", "--json", *args], env=env,
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        return json.loads(r.stdout)

    assert vtable_warm()["running"] is False
    r = subprocess.run([*DIAGNOSE, "--help"], env=env, capture_output=True, timeout=120)
    assert r.returncode == 0
    now = vtable_warm()
    pid = int(_servers(tmp)[0])
    assert (now["running"], now["pid"], now["enabled"]) == (True, pid, True)
    assert Path(now["log"]).read_text().count("listening") == 1
    assert vtable_warm("--stop") == {**now, "stopped": True}
    assert _gone(pid, 10) and _logged(tmp, "asked to stop")
    assert vtable_warm()["running"] is False


def test_a_signal_that_ends_the_command_ends_its_caller(warm, campaign):
    """SIGTERM to the caller reaches its command, which it ends; the caller then ends by
    SIGTERM too, as a process of its own would (-15 to its parent)."""
    env, tmp = warm
    p, _ = _started(env, campaign[1])
    p.send_signal(signal.SIGTERM)
    p.communicate(timeout=60)
    assert p.returncode == -signal.SIGTERM
    child = _children(tmp)[-1]
    assert _gone(child, 10) and _logged(tmp, f"pid {child}: signal {int(signal.SIGTERM)}")


def _help(env: dict, ignore: tuple = ()) -> None:
    """`vtable diagnose --help` from a caller ignoring the signals `ignore`."""
    r = subprocess.run([*DIAGNOSE, "--help"], env=env, capture_output=True, timeout=120,
                       preexec_fn=lambda: [signal.signal(s, signal.SIG_IGN if s in ignore
                                                         else signal.SIG_DFL)
                                           for s in (signal.SIGHUP, signal.SIGTERM)])
    assert r.returncode == 0


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_a_signal_the_caller_ignores_its_command_ignores_and_ctrl_z_stops_both(warm,
                                                                             campaign):
    """`nohup vtable diagnose ...` (the warm process started by another caller): the
    hangup ignored by the caller is ignored by its command, sent to the command's own
    process group, and the command runs to its end. On the way, Ctrl-Z (SIGTSTP to the
    caller) stops the command's process group, its workers included, and the caller, as
    the terminal stops a process of its own; continued (a shell's fg: SIGCONT to the
    caller), both go on."""
    env, tmp = warm
    _help(env)
    p, _ = _started(env, campaign[1], ignore=(signal.SIGHUP,))
    child = _children(tmp)[-1]
    try:
        os.killpg(child, signal.SIGHUP)
        p.send_signal(signal.SIGTSTP)
        assert _state(p.pid, "T") and _state(child, "T")
        time.sleep(0.3)
        group = _group(child)
        assert len(group) >= 1 + (WORKERS if WORKERS > 1 else 0)  # the command, its workers
        assert all(_state(pid, "T", 0.1) for pid in group)  # and stay so
        p.send_signal(signal.SIGCONT)
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err[-2000:]
        assert "error history" in out and _logged(tmp, f"pid {child}: exit 0")
    finally:  # nothing left stopped when an assertion fails
        for cont in (lambda: p.send_signal(signal.SIGCONT),
                     lambda: os.killpg(child, signal.SIGCONT)):
            with contextlib.suppress(ProcessLookupError):
                cont()
        if p.poll() is None:
            p.kill()
            p.communicate(timeout=30)


def test_a_signal_a_caller_heeds_ends_its_command_though_nohup_started_the_process(warm,
                                                                                   campaign):
    """The warm process started by a `nohup` caller: a later caller's hangup still ends its
    command, and the caller ends by it."""
    env, tmp = warm
    _help(env, ignore=(signal.SIGHUP,))
    p, _ = _started(env, campaign[1])
    p.send_signal(signal.SIGHUP)
    p.communicate(timeout=60)
    assert p.returncode == -signal.SIGHUP
    assert _logged(tmp, f"pid {_children(tmp)[-1]}: signal {int(signal.SIGHUP)}")


def test_the_command_has_the_environment_its_libraries_set_on_loading(warm, tmp_path):
    """What loading vtable puts in the environment (numba's cache folder, when the user
    gave none) is in a warm command's too: a user's effect file reads it there."""
    env, tmp = warm
    env = {k: v for k, v in env.items() if k != "NUMBA_CACHE_DIR"}
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    probe = tmp_path / "probe.py"
    probe.write_text("import os\nprint('cache:', os.environ.get('NUMBA_CACHE_DIR'))\n")
    said = []
    for how in ("0", "1", "1"):
        r = subprocess.run([*DIAGNOSE, "--effects-from", str(probe), "nothere.toml"],
                           env={**env, "VTABLE_WARM": how}, capture_output=True, text=True,
                           timeout=120)
        said.append((r.returncode, r.stdout, r.stderr))
    assert said[1] == said[0] and said[2] == said[0]
    assert f"cache: {tmp_path / 'cache'}" in said[0][1]
    assert len(_servers(tmp)) == 1


def test_a_new_environment_s_warm_process_ends_the_longest_idle(warm):
    """At most `MAX_PROCESSES` warm processes: a fourth environment's first command ends
    the one whose last command is oldest, and gets one of its own."""
    from vtable.warm import MAX_PROCESSES

    env, tmp = warm
    pids: list[int] = []  # each environment's warm process, in the order started
    for k in range(MAX_PROCESSES + 1):
        r = subprocess.run([*DIAGNOSE, "--help"], env={**env, "VTABLE_TEST_ENV": str(k)},
                           capture_output=True, timeout=120)
        assert r.returncode == 0
        pids += [int(p) for p in _servers(tmp) if int(p) not in pids]
        time.sleep(0.05)  # the logs' times apart
    assert len(pids) == MAX_PROCESSES + 1
    assert _gone(pids[0], 10) and _logged(tmp, f"[{pids[0]}] asked to stop")
    assert not any(_gone(p, 0.5) for p in pids[1:])


def test_what_is_not_a_command_is_dropped_and_a_deleted_socket_ends_the_warm_process(warm):
    """Bytes on the socket that are not a command (no streams passed, a header too long or
    cut short) are dropped, the warm process serving the next command as before; its
    socket deleted (a cleaner emptied the folder), it ends, and the next command starts a
    new one."""
    env, tmp = warm

    def diagnose_help() -> None:
        r = subprocess.run([*DIAGNOSE, "--help"], env=env, capture_output=True, text=True,
                           timeout=120)
        assert r.returncode == 0 and "usage: vtable diagnose" in r.stdout, r.stderr

    diagnose_help()
    (sock,) = tmp.glob("vtable-*/*.sock")
    pid = int(_servers(tmp)[0])
    for junk, fds, ended in ((b"not a command", [], False),
                             (struct.pack("!I", 1 << 30) + b"{}", [0, 1, 2], False),
                             (struct.pack("!I", 100) + b'{"argv": ', [0, 1, 2], True)):
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(3.0)  # dropped at once (the warm process waits 5 s for the rest)
            s.connect(str(sock))
            socket.send_fds(s, [junk], fds)
            if ended:  # cut short: no more is coming
                s.shutdown(socket.SHUT_WR)
            assert s.recv(100) == b""  # closed without a word
    diagnose_help()
    assert _servers(tmp) == [str(pid)] and _logged(tmp, ": exit 0", 2)
    sock.unlink()
    assert _gone(pid, 10) and _logged(tmp, "its socket is gone")
    diagnose_help()
    assert len(_servers(tmp)) == 2
