"""The warm process (`vtable.warm`), started by a caller (`vtable.warm.client`) with its
module search path; `vtable.warm.boot.boot` has taken the lock next to its socket (one warm
process per socket) before this module's imports. It imports what a diagnosis needs,
then listens. Each connection
brings one command: a header (its length in 4 bytes, then JSON: argv, cwd, env, umask,
unbuffered, the signals its caller ignores) with the caller's standard streams attached
(SCM_RIGHTS). The process answers ``pid N`` after forking the command's child (its own
process group: the caller signals the group), then ``exit N``, or ``signal N`` if a signal
ended it; or ``stale`` when a module it loaded has changed on disk since (then it stops
taking commands, lets its children finish and ends). It is single-threaded (a fork copies
only the forking thread): one `select` on the socket and on the wake-up pipe SIGCHLD and
SIGTERM write to. SIGINT stays blocked here and in a child until its command runs
(`_child`), so an early Ctrl-C waits for the command instead of being lost.

After each diagnosis it builds, between commands, every model the diagnosis built
(`_lessons`), loading their compiled kernels here: the next command's child and the Dask
workers it forks start with them.
"""

from __future__ import annotations

import contextlib
import fcntl
import gc
import io
import json
import os
import pickle
import select
import signal
import socket
import struct
import sys
import threading
import time
import traceback
from pathlib import Path

import vtable.cli
from vtable import verbs
from vtable.__main__ import _collect, _end, start
from vtable.diagnose.workers import WARM_SAMPLES, load_kernels
from vtable.errors import on_sigint
from vtable.models.reduced import ReducedModel
from vtable.runs import parsed
from vtable.runs.csvfile import parse_csv
from vtable.runs.lab import run_table
from vtable.warm import IDLE_S, VERBS

#: the longest header a command may bring (its environment included)
_HEADER_MAX = 1 << 20

#: the most kernel sets a warm process loads from what its commands built (`_lessons`)
_BUILT_MAX = 500


class _Modules:
    """The files of the modules this process has loaded, with their sizes and times:
    `changed` names one that is no longer as it was."""

    def __init__(self) -> None:
        self.files = {f: self._stamp(f) for f in self._paths()}

    @staticmethod
    def _paths() -> set[str]:
        return {f for m in list(sys.modules.values())
                if isinstance(f := getattr(m, "__file__", None), str)}

    @staticmethod
    def _stamp(path: str) -> tuple[int, int] | None:
        try:
            st = os.stat(path)
        except OSError:
            return None
        return st.st_mtime_ns, st.st_size

    def changed(self) -> str | None:
        """The first file found changed, or None."""
        return next((f for f, s in self.files.items() if self._stamp(f) != s), None)


def _receive(conn: socket.socket) -> tuple[dict, list[int]]:
    """A command's header and the caller's three stream descriptors (closed here if the
    header is not whole)."""
    data, fds, _, _ = socket.recv_fds(conn, 65536, 3)
    try:
        if len(fds) != 3 or len(data) < 4:
            raise ValueError("no header or no streams")
        n = struct.unpack("!I", data[:4])[0]
        if n > _HEADER_MAX:
            raise ValueError("header too long")
        data = data[4:]
        while len(data) < n:
            more = conn.recv(n - len(data))
            if not more:
                raise ValueError("header cut short")
            data += more
        return json.loads(data), fds
    except (OSError, ValueError):
        for fd in fds:
            os.close(fd)
        raise


def _peer_uid(conn: socket.socket) -> int | None:
    """The connecting process's user (Linux's SO_PEERCRED), None where it cannot be read:
    the socket's folder is the user's alone (`vtable.warm.place`) either way."""
    if not hasattr(socket, "SO_PEERCRED"):
        return None
    creds = conn.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i"))
    return struct.unpack("3i", creds)[1]


def _streams(unbuffered: bool) -> None:
    """sys.stdin, stdout, stderr anew on descriptors 0-2 (now the caller's), as Python
    makes them at start-up: stdout line-buffered on a terminal, stderr by lines, both
    written through under ``-u`` or ``PYTHONUNBUFFERED``."""
    for name, fd, mode in (("stdin", 0, "rb"), ("stdout", 1, "wb"), ("stderr", 2, "wb")):
        old = getattr(sys, name)
        raw = open(fd, mode, buffering=0 if unbuffered and fd else -1, closefd=False)
        stream = io.TextIOWrapper(raw, encoding=old.encoding, errors=old.errors,
                                  line_buffering=fd == 2 or (fd == 1 and os.isatty(fd)),
                                  write_through=unbuffered and fd > 0)
        setattr(sys, name, stream)
        setattr(sys, f"__{name}__", stream)


def _lessons(result) -> list[tuple]:
    """What a diagnosis built, for the warm process to build too (`_Server.build_one`):
    each model it went through or tried, once per set of effects, with the runs' table and
    a few samples of the first run. Their compiled kernels are then loaded in the warm
    process, and the next command's child and its workers start with them (fork), not
    loading them each (~0.45 s of a README diagnosis's 4.9 s)."""
    rounds, runs = getattr(result, "rounds", None), getattr(result, "runs", None)
    if not rounds or not runs:
        return []
    models = {}
    for ph in [s.physics for s in result.stages] + [c.physics for r in rounds
                                                     for c in r.ranking]:
        models.setdefault(tuple(sorted(ph.effects)), ph)
    run = runs[0]
    try:
        table, x = run_table(run), run.channel("h_span")[:WARM_SAMPLES].copy()
    except Exception:  # nothing to learn from a run the table cannot read
        return []
    return [(ph, table, run.time[:WARM_SAMPLES].copy(), x) for ph in models.values()]


def _child(conn: socket.socket, head: dict, fds: list[int], loaded_env: dict) -> None:
    """Run the command in this forked child, as `vtable.__main__.run` would, and end."""
    os.setpgid(0, 0)  # its own group: the caller's signals reach it and its workers
    for i, fd in enumerate(fds):
        os.dup2(fd, i)
        os.close(fd)
    os.environ.clear()
    os.environ.update({**head["env"], **loaded_env})
    os.umask(head["umask"])
    _streams(bool(head["unbuffered"] or os.environ.get("PYTHONUNBUFFERED")))
    try:
        os.chdir(head["cwd"])
    except OSError as e:
        print(f"vtable: error: cannot enter {head['cwd']}: {e.strerror}", file=sys.stderr)
        _end(2)
    sys.argv = ["vtable", *head["argv"]]
    start()
    for s in (signal.SIGHUP, signal.SIGTERM, signal.SIGTSTP):  # as the caller has them
        signal.signal(s, signal.SIG_IGN if s in head["ignored"] else signal.SIG_DFL)
    if signal.SIGINT in head["ignored"]:  # (`nohup`, a shell's background job)
        signal.signal(signal.SIGINT, signal.SIG_IGN)

    def watch() -> None:  # the caller gone (killed outright): the command stops
        with contextlib.suppress(OSError):
            while conn.recv(64):
                pass
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=watch, daemon=True, name="vtable-warm-caller").start()
    lessons: list = []
    parsed.noting()  # the run files it parses: for this process to parse for the next

    def loaded() -> None:  # the command runs: an interrupt is its own from now on
        _collect()
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})

    def finish(code: int) -> None:
        """The caller's streams let go (a pipe it reads ends now), its exit code told, and
        what this command's models were left for the warm process (`_lessons`)."""
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # the caller ends once told (`watch`)
        null = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(null, fd)
        _say(conn, f"exit {code}")
        lessons.extend(("csv", p) for p in parsed.parsed_here())
        if lessons:
            tmp = Path(f"{head['lessons']}.tmp")
            with contextlib.suppress(OSError, pickle.PicklingError, TypeError):
                tmp.write_bytes(pickle.dumps(lessons))
                tmp.rename(head["lessons"])

    try:
        code = vtable.cli.main(head["argv"], loaded=loaded,
                               done=lambda result: lessons.extend(_lessons(result)))
    except SystemExit as e:  # argparse's --help and its errors
        if isinstance(e.code, str):
            print(e.code, file=sys.stderr)
        code = e.code if isinstance(e.code, int) else int(e.code is not None)
    except BaseException:  # what `python -m vtable` would print
        traceback.print_exc()
        code = 1
    _end(code, then=finish)


class _Server:
    """The listening socket, its lock and log, the wake-up pipe and the running children."""

    def __init__(self, path: Path, lock, loaded_env: dict) -> None:
        self.path, self.lock, self.loaded_env = path, lock, loaded_env
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
        self.listener: socket.socket | None = socket.socket(socket.AF_UNIX,
                                                            socket.SOCK_STREAM)
        self.listener.bind(str(path))
        self.listener.listen(16)
        self.inode = os.stat(path).st_ino
        self.wake_r, self.wake_w = os.pipe()
        os.set_blocking(self.wake_w, False)
        signal.set_wakeup_fd(self.wake_w)
        signal.signal(signal.SIGCHLD, lambda *_: None)
        self.stopped = False  # SIGTERM (`vtable.warm.stop`): no more commands
        signal.signal(signal.SIGTERM, self._stop)
        self.children: dict[int, socket.socket] = {}
        self.todo: list[tuple] = []  # models to build (`learn`)
        self.built: set = set()  # the kernels' keys built so
        self.log = open(f"{path}.log", "a", buffering=1)  # the process's
        self.say("listening")

    def say(self, line: str) -> None:
        """A line in the log beside the socket (`<socket>.log`, where a warm process's
        start-up errors go too): what it ran, what it learnt, why it ended."""
        with contextlib.suppress(OSError):
            self.log.write(f"{time.strftime('%H:%M:%S')} [{os.getpid()}] {line}\n")

    def _stop(self, signum, frame) -> None:
        self.stopped = True

    def learn(self, pid: int) -> None:
        """Queue what the ended child `pid` left (`_lessons`)."""
        path = self.lessons(pid)
        with contextlib.suppress(OSError, pickle.UnpicklingError, EOFError, AttributeError,
                                 ImportError, TypeError, ValueError):
            self.todo += pickle.loads(path.read_bytes())
        path.unlink(missing_ok=True)
        Path(f"{path}.tmp").unlink(missing_ok=True)  # `finish` cut short

    def lessons(self, pid: int) -> Path:
        return self.path.with_name(f"{self.path.name}.{pid}.lessons")

    def build_one(self) -> None:
        """Build one queued model and simulate its few samples, its kernels loaded (or
        compiled) here, if no model built before had them; a model that cannot be built
        here (a user's effect) is passed over. Or parse a run file a command read, for the
        next (`vtable.runs.parsed`)."""
        lesson = self.todo.pop(0)
        try:
            if isinstance(lesson[0], str):  # ("csv", its absolute path)
                self.say(f"{lesson[1]}: "
                         f"{'parsed' if parsed.keep(lesson[1], parse_csv) else 'not kept'}")
            else:
                ph, table, t, x = lesson
                m = ReducedModel(ph, table)
                key = (m.element.key, m.M.shape, m.Aw.shape, m.elem is None)
                if key not in self.built and len(self.built) < _BUILT_MAX:
                    self.built.add(key)
                    load_kernels(m, t, x)
        except Exception:  # the child reported what it could not do
            pass
        if not self.todo:
            self.say(f"{len(self.built)} kernel sets loaded")
            gc.freeze()  # what was built is the children's: out of the collector's sight

    def orphaned(self) -> bool:
        """Whether its socket's path is gone or another's (a cleaner emptied the folder)."""
        try:
            return os.stat(self.path).st_ino != self.inode
        except OSError:
            return True

    def run(self, modules: _Modules) -> None:
        last = time.monotonic()
        while self.listener is not None or self.children:
            if self.listener is not None and (self.stopped or self.orphaned()):
                self.say("asked to stop" if self.stopped else "its socket is gone")
                self.close()
                continue
            waiting = [self.wake_r] + ([self.listener] if self.listener is not None else [])
            busy = bool(self.todo) and self.listener is not None
            ready, _, _ = select.select(waiting, [], [], 0.0 if busy else 1.0)
            if self.wake_r in ready:
                with contextlib.suppress(BlockingIOError):
                    os.read(self.wake_r, 512)
            self.reap()
            if self.children:
                last = time.monotonic()
            if self.listener is not None and self.listener in ready:
                conn, _ = self.listener.accept()
                last = time.monotonic()
                if (changed := modules.changed()) is not None:
                    self.say(f"{changed} changed: no more commands")
                    self.close()  # first: the caller's next try starts a new one
                    _say(conn, "stale")
                    conn.close()
                else:
                    self.start(conn)
            elif busy:
                self.build_one()
            elif self.listener is not None and time.monotonic() - last > IDLE_S:
                self.say(f"no command for {IDLE_S:.0f} s")
                self.close()

    def start(self, conn: socket.socket) -> None:
        """Fork one command's child (`_child`) and tell the caller its pid."""
        try:
            if _peer_uid(conn) not in (None, os.getuid()):
                raise ValueError("another user's command")
            conn.settimeout(5.0)
            head, fds = _receive(conn)
            conn.settimeout(None)
        except (OSError, ValueError):
            conn.close()
            return
        pid = os.fork()
        if pid == 0:
            try:
                self.listener.close()
                for other in self.children.values():
                    other.close()
                self.lock.close()
                self.log.close()
                signal.set_wakeup_fd(-1)
                for s in (signal.SIGCHLD, signal.SIGTERM):
                    signal.signal(s, signal.SIG_DFL)
                os.close(self.wake_r)
                os.close(self.wake_w)
                _child(conn, {**head, "lessons": str(self.lessons(os.getpid()))}, fds,
                       self.loaded_env)
            finally:
                os._exit(1)
        for fd in fds:
            os.close(fd)
        with contextlib.suppress(OSError):
            os.setpgid(pid, pid)  # as the child does: the caller may signal it at once
        _say(conn, f"pid {pid}")
        self.children[pid] = conn
        self.say(f"pid {pid}: vtable {' '.join(head['argv'])} (in {head['cwd']})")

    def reap(self) -> None:
        """Tell each caller whose child has ended how it ended (its exit code, told by the
        child already, or the signal that ended it)."""
        for pid in list(self.children):
            done, status = os.waitpid(pid, os.WNOHANG)
            if done:
                how = (f"exit {os.WEXITSTATUS(status)}" if os.WIFEXITED(status)
                       else f"signal {os.WTERMSIG(status)}")
                conn = self.children.pop(pid)
                _say(conn, how)
                conn.close()
                self.say(f"pid {pid}: {how}")
                self.learn(pid)

    def close(self) -> None:
        """Stop taking commands: the socket removed (if still this process's) and the lock
        released, so that a new warm process may start while the children finish."""
        if not self.orphaned():
            with contextlib.suppress(OSError):
                self.path.unlink()
        self.listener.close()
        self.listener = None
        fcntl.flock(self.lock, fcntl.LOCK_UN)


def _say(conn: socket.socket, line: str) -> None:
    with contextlib.suppress(OSError):  # the caller gone: nobody to tell
        conn.sendall(f"{line}\n".encode())


def main(path: Path, lock, given: dict[str, str]) -> None:
    """The warm process on `path`, its lock held (`vtable.warm.boot.boot`), started with the
    environment `given`: load, listen, and answer commands until `IDLE_S` seconds pass
    with no command and no child, a loaded module changes, or SIGTERM. What loading set
    in the environment (numba's cache folder, `vtable._numba`), each command's
    environment gets too."""
    for verb in VERBS:
        getattr(verbs, verb)  # its modules imported (`vtable.verbs`)
    loaded_env = {k: v for k, v in os.environ.items() if given.get(k) != v}
    gc.freeze()
    gc.enable()
    # SIGINT: the CLI's handler, blocked until a child's command runs (module docstring)
    signal.signal(signal.SIGINT, on_sigint)
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    server = _Server(path, lock, loaded_env)
    server.run(_Modules())
    server.say("ended")
