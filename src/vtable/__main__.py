"""`python -m vtable` and the `vtable` command: the CLI, with an interrupt during start-up
(while the libraries load) ending as quietly as one during a command.

The command renders nothing with MuJoCo (its views are Rerun's), so MuJoCo's OpenGL
back-end is not looked for (``MUJOCO_GL=disable`` unless the user has set it): on Linux
that search runs a second Python interpreter to read GLFW's version, which costs start-up
time and, when Ctrl-C reaches the process group while it starts, prints
"Fatal Python error: init_import_site" with its traceback.

The garbage collector is off while the command's libraries load (`main`'s `loaded`): what
an import makes lives as long as the process, and the collections that walked it as it
grew cost a diagnosis's start 0.17 s (1.31 → 1.14 s, `vtable diagnose` of a missing file);
then it is frozen out of the collector's sight (`gc.freeze`) and the collector runs.

`vtable diagnose` is first offered to the warm process (`vtable.warm`): where one answers,
this process only waits for its command's end and ends as it did; else (or with
``VTABLE_WARM=0``) the command runs here.

A command that returns ends as Python would end it (other threads joined, exit handlers
run: the diagnosis's workers stopped, OpenSees quieted; the streams flushed), without the
interpreter's teardown, which frees every object one by one: 0.3 s after a diagnosis, for
nothing (every file a command writes is closed or flushed when it returns: `vtable.fileio`,
`vtable.viz.recording`)."""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import gc
import os
import signal
import sys
import threading
from collections.abc import Callable

from vtable.errors import interrupted, on_sigint, sigint_seen
from vtable.warm import CLI_DEFAULTS
from vtable.warm.client import served


def _quiet_interrupts(u) -> None:
    """An interrupt Python cannot raise (in an import's lock callback) is not printed as a
    traceback: `on_sigint` has remembered it, and the command ends on it in one line."""
    if not isinstance(u.exc_value, KeyboardInterrupt):
        sys.__unraisablehook__(u)


def start() -> None:
    """The command's process settings (module docstring): Ctrl-C raised and remembered,
    MuJoCo's OpenGL back-end not looked for, an interrupt in a callback not printed."""
    signal.signal(signal.SIGINT, on_sigint)
    for name, value in CLI_DEFAULTS.items():
        os.environ.setdefault(name, value)
    sys.unraisablehook = _quiet_interrupts


def run() -> None:
    signal.signal(signal.SIGINT, on_sigint)  # first: an interrupt while loading is seen
    try:
        code = served(sys.argv[1:])  # in the warm process (`vtable.warm`), if it is for it
    except KeyboardInterrupt:
        print("vtable: interrupted", file=sys.stderr)
        sys.exit(130)
    if code is not None:
        with contextlib.suppress(OSError, ValueError):
            sys.stderr.flush()
        os._exit(code)
    gc.disable()  # while the libraries load (module docstring)
    start()
    try:
        from vtable.cli import main  # in the try: Ctrl-C while the libraries load
    except Exception as e:  # a library's own error once Ctrl-C came: the interrupt (`main`)
        if not (interrupted(e) or sigint_seen()):
            raise
        print("vtable: interrupted", file=sys.stderr)
        sys.exit(130)
    except KeyboardInterrupt:
        print("vtable: interrupted", file=sys.stderr)
        sys.exit(130)
    _end(main(loaded=_collect))


def _collect() -> None:
    """The command's libraries loaded: what they made lives as long as the process, out
    of the collector's sight from now on (`gc.freeze`); the collector runs again."""
    gc.freeze()
    gc.enable()


def _end(code: int, then: Callable[[int], None] | None = None) -> None:
    """Exit with `code` without the interpreter's teardown (module docstring): first what
    Python's exit does (threads' exit hooks and joins, then the exit handlers), the
    streams flushed, Python's and C's. A closed pipe then is 141, a Ctrl-C meanwhile 130
    (said in one line), another failed flush of stdout 120 (Python's own). `then` is
    called with the code last (the warm process's child: `vtable.warm.server`)."""
    interrupted = False
    for step in (threading._shutdown, atexit._run_exitfuncs):
        try:
            step()
        except KeyboardInterrupt:  # the handlers still run after an interrupted join
            interrupted = True
    if code == 0 and (interrupted or sigint_seen()):  # a handler's interrupt is swallowed
        print("vtable: interrupted", file=sys.stderr)
        code = 130
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        from vtable.cli import quiet_stdout  # loaded by now

        quiet_stdout()
        code = code or 141
    except (OSError, ValueError):
        code = code or 120
    with contextlib.suppress(OSError, ValueError):
        sys.stderr.flush()
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).fflush(None)  # what C libraries (OpenSees, MuJoCo) left buffered
    if then is not None:
        then(code)
    os._exit(code)


if __name__ == "__main__":
    run()
