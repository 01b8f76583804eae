"""The caller's side of the warm process (`vtable.warm`): hand it a command, pass it the
signals this process gets, and end as its command ended.

Only the standard library is imported here: a command the warm process answers costs this
process no library's start-up."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

from vtable.warm import WarmSettingError, here, place, search_path, wanted

#: seconds a caller waits for a warm process it started to listen (its imports, on a busy
#: machine) before running the command itself
START_S = 60.0

#: a warm process's log is begun anew past this size (bytes)
_LOG_MAX = 1 << 20

#: the signals a caller passes on to its command (its process group), unless it ignores
#: them itself (`nohup`, a shell's background job): those its command ignores too
_PASSED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGTSTP)

#: how the warm process is started: the collector off while it loads, the caller's module
#: search path, the `vtable` command's settings (`vtable.__main__`), the signals a `nohup`
#: caller ignored at their defaults (each command sets its caller's), the environment as
#: given (what loading adds to it, each command gets: `vtable.warm.server.main`)
_BOOT = ("import gc, json, os, signal, sys; gc.disable(); env = dict(os.environ); "
         "sys.path[:] = json.loads(sys.argv[1]); from vtable.warm import CLI_DEFAULTS; "
         "[os.environ.setdefault(k, v) for k, v in CLI_DEFAULTS.items()]; "
         "[signal.signal(s, signal.SIG_DFL) for s in (signal.SIGHUP, signal.SIGTSTP)]; "
         "from vtable.warm.boot import boot; boot(sys.argv[2], sys.argv[3], env)")


def served(argv: list[str]) -> int | None:
    """Run the command `argv` (without the program's name) in the warm process and return
    its exit code, or None when it is to run in this process: not a warm verb,
    ``VTABLE_WARM=0``, no safe socket folder, or no warm process to be had before its
    command began. A bad ``VTABLE_WARM`` is said in one line (exit code 2). A command the
    warm process ended by a signal ends this process by that signal."""
    try:
        if not wanted(argv):
            return None
    except WarmSettingError as e:
        print(f"vtable: error: {e}", file=sys.stderr)
        return 2
    try:
        path = place()
        if path is None:
            return None
        for _ in range(2):  # a second time after a stale warm process has stepped aside
            conn = _connect(path) or _started(path)
            if conn is None:
                return None
            with conn:
                code = _through(conn, argv)
            if code is not None:
                return code
    except OSError:  # no working folder, no socket, no process to start: run here
        return None
    return None


def _connect(path: Path) -> socket.socket | None:
    conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        conn.connect(str(path))
    except OSError:
        conn.close()
        return None
    return conn


def _started(path: Path) -> socket.socket | None:
    """Start a warm process on `path` (`vtable.warm.boot.boot`) and connect once it listens;
    None if it ended without listening (another one took the socket meanwhile, and does
    not listen within a few seconds either), or did not listen within `START_S`."""
    log = Path(f"{path}.log")
    with contextlib.suppress(OSError):
        if log.stat().st_size > _LOG_MAX:
            log.unlink()
    with open(log, "ab") as out:  # what it says on starting, if it fails
        server = subprocess.Popen(  # its own session: the terminal's Ctrl-C is not for it
            [sys.executable, "-c", _BOOT, json.dumps(search_path()), str(path), here()],
            stdin=subprocess.DEVNULL, stdout=out, stderr=out, start_new_session=True,
            cwd=path.parent)
    deadline = time.monotonic() + START_S
    while time.monotonic() < deadline:
        conn = _connect(path)
        if conn is not None:
            return conn
        code = server.poll()
        if code not in (None, 0):
            return None  # it failed (what it said is in its log)
        if code == 0:  # another one has the lock: it lists soon, or never
            deadline = min(deadline, time.monotonic() + 5.0)
        time.sleep(0.01)
    return None


def _through(conn: socket.socket, argv: list[str]) -> int | None:
    """Send the command with this process's streams, pass on signals until it ends, and
    return its exit code; None if it never began (the warm process stale or gone)."""
    mask = os.umask(0)
    os.umask(mask)
    passed = [s for s in _PASSED if signal.getsignal(s) is not signal.SIG_IGN]
    head = json.dumps({"argv": argv, "cwd": os.getcwd(), "env": dict(os.environ),
                       "umask": mask, "unbuffered": bool(getattr(sys.stdout, "write_through", 0)),
                       "ignored": [int(s) for s in _PASSED if s not in passed]}).encode()
    data = struct.pack("!I", len(head)) + head
    try:
        sent = socket.send_fds(conn, [data], [0, 1, 2])
        conn.sendall(data[sent:])
    except OSError:  # a stream closed here, or the warm process gone
        return None
    child: list[int] = []
    pending: list[int] = []  # signals that came before the command's pid
    before = {s: signal.getsignal(s) for s in passed}

    def pass_on(signum, frame) -> None:
        if not child:  # passed on as soon as its pid comes (`_outcome`); a second Ctrl-C
            if signum == signal.SIGINT and signum in pending:  # meanwhile ends this
                raise KeyboardInterrupt  # process, and so the command
            pending.append(signum)
            return
        with contextlib.suppress(ProcessLookupError):
            os.killpg(child[0], signum)
        if signum == signal.SIGTSTP:  # stop here too, as the terminal asked; then go on
            signal.signal(signal.SIGTSTP, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGTSTP)
            signal.signal(signal.SIGTSTP, pass_on)
            with contextlib.suppress(ProcessLookupError):
                os.killpg(child[0], signal.SIGCONT)

    for s in passed:
        signal.signal(s, pass_on)
    try:
        code = _outcome(conn, child, lambda: [pass_on(s, None) for s in pending])
        if code is None and pending:  # it never began: the signal is this process's
            if signal.SIGINT in pending:
                raise KeyboardInterrupt
            _die(pending[0])
        return code
    finally:
        for s, handler in before.items():
            signal.signal(s, handler)


def _outcome(conn: socket.socket, child: list[int], begun) -> int | None:
    """Read the warm process's lines: the command's pid (then `begun()`), then how it
    ended."""
    try:
        for line in conn.makefile("r", encoding="ascii"):
            word, _, value = line.strip().partition(" ")
            if word == "stale":
                return None
            if word == "pid":
                child.append(int(value))
                begun()
            elif word == "exit":
                return int(value)
            elif word == "signal":
                _die(int(value))
                return 128 + int(value)
    except OSError:
        pass
    if not child:
        return None  # the warm process ended before it forked: run here
    print(f"vtable: error: the warm process ended before its command (pid {child[0]}) did;"
          " VTABLE_WARM=0 runs commands without it", file=sys.stderr)
    return 1


def _die(signum: int) -> None:
    """End this process by `signum`, as its command was (a caller reads -N, a shell says
    why)."""
    with contextlib.suppress(OSError, ValueError):  # SIGKILL's cannot be set
        signal.signal(signum, signal.SIG_DFL)
    with contextlib.suppress(OSError, ValueError):
        sys.stderr.flush()
    os.kill(os.getpid(), signum)
