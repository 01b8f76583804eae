"""The caller's side of the warm process (`vtable.warm`): hand it a command, wait for its
exit code, pass it the signals this process gets.

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

from vtable.warm import WarmSettingError, place, wanted

#: seconds a caller waits for a warm process it started to listen (its imports, on a busy
#: machine) before running the command itself
START_S = 60.0

#: a warm process's log is begun anew past this size (bytes)
_LOG_MAX = 1 << 20

#: the signals a caller passes on to its command's child
_PASSED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def served(argv: list[str]) -> int | None:
    """Run the command `argv` (without the program's name) in the warm process and return
    its exit code, or None when it is to run in this process: not a warm verb,
    ``VTABLE_WARM=0``, no safe socket folder, or no warm process to be had. A bad
    ``VTABLE_WARM`` is said in one line (exit code 2)."""
    try:
        if not wanted(argv):
            return None
    except WarmSettingError as e:
        print(f"vtable: error: {e}", file=sys.stderr)
        return 2
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
    """Start a warm process on `path` and connect once it listens; None if it ended
    without listening (another one took the socket meanwhile: connect to that one) or did
    not listen within `START_S`."""
    log = Path(f"{path}.log")
    with contextlib.suppress(OSError):
        if log.stat().st_size > _LOG_MAX:
            log.unlink()
    with open(log, "ab") as out:  # what it says on starting, if it fails
        server = subprocess.Popen(  # its own session: the terminal's Ctrl-C is not for it
            [sys.executable, "-m", "vtable.warm.server", str(path)],
            stdin=subprocess.DEVNULL, stdout=out, stderr=out, start_new_session=True,
            cwd=path.parent)
    deadline = time.monotonic() + START_S
    while time.monotonic() < deadline:
        conn = _connect(path)
        if conn is not None:
            return conn
        if server.poll() not in (None, 0):
            return None  # it failed (a broken installation shows in this process)
        time.sleep(0.01)
    return None


def _through(conn: socket.socket, argv: list[str]) -> int | None:
    """Send the command with this process's streams, pass on signals until it ends, and
    return its exit code; None if the warm process was stale."""
    mask = os.umask(0)
    os.umask(mask)
    head = json.dumps({"argv": argv, "cwd": os.getcwd(), "env": dict(os.environ),
                       "umask": mask, "nice": os.getpriority(os.PRIO_PROCESS, 0)}).encode()
    data = struct.pack("!I", len(head)) + head
    try:
        sent = socket.send_fds(conn, [data], [0, 1, 2])
        conn.sendall(data[sent:])
    except OSError:  # a stream closed here, or the warm process gone
        return None
    child: list[int] = []
    pending: list[int] = []

    def pass_on(signum, frame) -> None:
        if child:
            with contextlib.suppress(ProcessLookupError):
                os.kill(child[0], signum)
        else:
            pending.append(signum)

    for s in _PASSED:
        signal.signal(s, pass_on)
    lines = conn.makefile("r", encoding="ascii")
    for line in lines:
        word, _, value = line.strip().partition(" ")
        if word == "stale":
            return None
        if word == "pid":
            child.append(int(value))
            for s in pending:
                pass_on(s, None)
        elif word == "exit":
            return int(value)
    if not child:
        return None  # the warm process ended before it forked: run here
    print(f"vtable: error: the warm process ended before its command (pid {child[0]}) did;"
          " VTABLE_WARM=0 runs commands without it", file=sys.stderr)
    return 1
