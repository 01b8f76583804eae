"""The warm process: `vtable diagnose` without the libraries' start-up each time.

A diagnosis's own work on the README campaign is ~4 s on this project's 2-core machine; a
fresh `vtable diagnose` spent ~1.2 s more before it began (importing SciPy, Dask, numba
and vtable), every time. The first `vtable diagnose` in an environment therefore starts a
warm process (`vtable.warm.server`): a Python with those libraries imported, listening on
a socket private to the user. This and every later `vtable diagnose` (`vtable.warm.client`)
hands it the command line, the working folder, the environment and its own standard
streams; the warm process forks a child that runs the command exactly as the `vtable`
command would, writing straight to the caller's terminal or pipes, and the caller exits
with the child's exit code (or by the signal that ended it). Ctrl-C, Ctrl-Z and the
signals that end a process reach the child's process group (it and its Dask workers); a
caller killed outright stops its child.

One warm process per environment (`place`: the interpreter and its prefix, vtable's
location, the module search path, the process's priority, CPU affinity and resource
limits, and every environment variable but the shell's own bookkeeping, hashed), so a
command never runs with another environment's settings (``NUMBA_CACHE_DIR``, Dask's
configuration, thread counts, ``nice``); at most `MAX_PROCESSES` live at once (starting
another ends the one whose last command is oldest). It answers
a command only while no module it has loaded has changed on disk (vtable upgraded or
edited, a library upgraded): otherwise it hands the command back, stops, and a new one
starts. It ends after `IDLE_S` seconds without a command.

``VTABLE_WARM=0`` runs every command in its own process, as before (the test suite does);
``VTABLE_WARM=1`` (or unset) uses the warm process. Only ``vtable diagnose`` goes through it:
the verb a lab runs again and again as it adds effects and refits.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import signal
import socket
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

try:
    import fcntl
    import resource
except ImportError:  # not POSIX: no warm process (`wanted`)
    fcntl = resource = None

#: seconds a warm process waits for a command before it ends
IDLE_S = 600.0

#: the most warm processes (environments) of one user alive at once
MAX_PROCESSES = 3

#: the verbs handed to the warm process
VERBS = ("diagnose",)

#: what the `vtable` command sets in its environment unless the user has
#: (`vtable.__main__`): part of every command's environment, so of its key (`place`)
CLI_DEFAULTS = {"MUJOCO_GL": "disable"}

#: environment variables that differ between two shells of one environment, or that
#: only say whether to use it, left out of its key (`place`)
_SHELL_VARS = ("PWD", "OLDPWD", "_", "SHLVL", "VTABLE_WARM")

#: the longest socket path AF_UNIX takes (108 bytes on Linux, less elsewhere)
_SOCKET_PATH_MAX = 100


class WarmSettingError(ValueError):
    """``VTABLE_WARM`` holds something other than 0 or 1."""


def wanted(argv: list[str], environ: dict[str, str] | os._Environ = os.environ) -> bool:
    """Whether the command `argv` (without the program's name) goes through the warm
    process: its verb is one of `VERBS`, ``VTABLE_WARM`` is 1 or unset (another value is
    a `WarmSettingError` then), and this platform can hand a process's streams to another
    (POSIX sockets with descriptor passing)."""
    if not argv or argv[0] not in VERBS:
        return False
    setting = environ.get("VTABLE_WARM", "1")
    if setting not in ("0", "1"):
        raise WarmSettingError(f"VTABLE_WARM must be 0 or 1, not {setting!r}")
    return (setting == "1" and fcntl is not None and hasattr(os, "fork")
            and hasattr(socket, "send_fds"))


def here() -> str:
    """The folder of the vtable package this process runs."""
    return str(Path(__file__).resolve().parents[1])


def search_path() -> list[str]:
    """This process's module search path, each entry absolute ('' is the working folder)."""
    return [os.path.abspath(p) for p in sys.path]


def _process() -> list:
    """What a process inherits from its parent besides the environment and that a command
    reads: its priority, CPU affinity and resource limits."""
    cpus = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    limits = sorted((name, resource.getrlimit(getattr(resource, name)))
                    for name in dir(resource) if name.startswith("RLIMIT_"))
    return [os.getpriority(os.PRIO_PROCESS, 0), cpus, limits]


def place(environ: dict[str, str] | os._Environ = os.environ) -> Path | None:
    """The socket of this environment's warm process (`<tmp>/vtable-<uid>/<key>.sock`, the
    folder the user's alone), or None when no such folder can be made safely or its path
    is too long for a socket."""
    env = {**CLI_DEFAULTS, **{k: v for k, v in environ.items() if k not in _SHELL_VARS}}
    python = [os.path.realpath(sys.executable), sys.prefix, sys.version]  # python, python3
    key = hashlib.sha256(json.dumps([*python, here(), search_path(), _process(),
                                     sorted(env.items())]).encode()).hexdigest()[:16]
    folder = Path(environ.get("TMPDIR") or tempfile.gettempdir()) / f"vtable-{os.getuid()}"
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
        st = folder.lstat()
    except OSError:
        return None
    if st.st_uid != os.getuid() or st.st_mode & 0o077 or not folder.is_dir():
        return None
    path = folder / f"{key}.sock"
    return path if len(os.fsencode(path)) <= _SOCKET_PATH_MAX else None


def holder(path: Path) -> int | None:
    """The pid of the warm process that holds `path`'s lock (its pid is written there), or
    None when none does."""
    try:
        with open(f"{path}.lock") as lock:
            try:  # free: no warm process
                fcntl.flock(lock, fcntl.LOCK_SH | fcntl.LOCK_NB)
                return None
            except OSError:
                return int(lock.read().strip() or 0) or None
    except (OSError, ValueError):
        return None


def make_room(folder: Path) -> None:
    """At most `MAX_PROCESSES` warm processes of this user left in `folder`, this one
    among them: the others whose last command is oldest (their log's time) asked to end
    (`stop`)."""
    live = []
    for lock in folder.glob("*.sock.lock"):
        path = Path(str(lock)[:-len(".lock")])
        if (pid := holder(path)) not in (None, os.getpid()):
            with contextlib.suppress(OSError):
                live.append((Path(f"{path}.log").stat().st_mtime, pid))
    for _, pid in sorted(live)[:max(0, len(live) - MAX_PROCESSES + 1)]:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signal.SIGTERM)


def stop(environ: dict[str, str] | os._Environ = os.environ) -> int | None:
    """Ask the warm process of the environment `environ` to end (it takes no more commands
    and ends once those it is running have): its pid, or None when there is none."""
    path = place(environ)
    pid = None if path is None else holder(path)
    if pid is None:
        return None
    try:
        os.kill(pid, signal.SIGTERM)
    except (ProcessLookupError, PermissionError):
        return None
    return pid


@dataclass
class WarmProcess:
    """This environment's warm process (`vtable warm`): its pid (None: none runs), its
    socket and log, whether it was just asked to stop, whether commands use it."""

    pid: int | None
    socket: Path | None
    stopped: bool = False
    enabled: bool = True
    files: list[Path] = field(default_factory=list)

    @classmethod
    def of(cls, stop_it: bool = False,
           environ: dict[str, str] | os._Environ = os.environ) -> WarmProcess:
        enabled = environ.get("VTABLE_WARM", "1") != "0"
        path = place(environ)
        if stop_it:
            return cls(stop(environ), path, True, enabled)
        return cls(None if path is None else holder(path), path, False, enabled)

    @property
    def log(self) -> Path | None:
        return None if self.socket is None else Path(f"{self.socket}.log")

    def to_json(self) -> dict[str, Any]:
        return {"running": self.pid is not None, "pid": self.pid,
                "socket": None if self.socket is None else str(self.socket),
                "log": None if self.log is None else str(self.log),
                "stopped": self.stopped, "enabled": self.enabled}

    def report(self) -> str:
        off = "" if self.enabled else " (VTABLE_WARM=0: commands run without it)"
        if self.pid is None:
            return ("no warm process for this environment: the next vtable diagnose starts "
                    f"one{off}")
        if self.stopped:
            return (f"asked the warm process (pid {self.pid}) to end: it takes no more "
                    "commands and ends once those it runs have")
        return (f"warm process pid {self.pid} answers vtable diagnose in this environment"
                f"{off}; it ends after {IDLE_S / 60:.0f} min without a command (vtable warm "
                f"--stop ends it now)\n  socket {self.socket}\n  log    {self.log}")

