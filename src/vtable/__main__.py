"""`python -m vtable` and the `vtable` command: the CLI, with an interrupt during start-up
(while the libraries load) ending as quietly as one during a command.

The command renders nothing with MuJoCo (its views are Rerun's), so MuJoCo's OpenGL
back-end is not looked for (``MUJOCO_GL=disable`` unless the user has set it): on Linux
that search runs a second Python interpreter to read GLFW's version, which costs start-up
time and, when Ctrl-C reaches the process group while it starts, prints
"Fatal Python error: init_import_site" with its traceback.

A command that returns ends as Python would end it (other threads joined, exit handlers
run: the diagnosis's workers stopped, OpenSees quieted; the streams flushed), without the
interpreter's teardown, which frees every object one by one: 0.3 s after a diagnosis, for
nothing (every file a command writes is closed or flushed when it returns: `vtable.fileio`,
`vtable.viz.recording`)."""

from __future__ import annotations

import atexit
import os
import signal
import sys
import threading

from vtable.errors import on_sigint


def _quiet_interrupts(u) -> None:
    """An interrupt Python cannot raise (in an import's lock callback) is not printed as a
    traceback: `on_sigint` has remembered it, and the command ends on it in one line."""
    if not isinstance(u.exc_value, KeyboardInterrupt):
        sys.__unraisablehook__(u)


def run() -> None:
    signal.signal(signal.SIGINT, on_sigint)  # first: an interrupt while loading is seen
    os.environ.setdefault("MUJOCO_GL", "disable")  # module docstring
    sys.unraisablehook = _quiet_interrupts
    try:
        from vtable.cli import main  # in the try: Ctrl-C while the libraries load
    except KeyboardInterrupt:
        print("vtable: interrupted", file=sys.stderr)
        sys.exit(130)
    _end(main())


def _end(code: int) -> None:
    """Exit with `code` without the interpreter's teardown (module docstring)."""
    try:
        for t in threading.enumerate():
            if t is not threading.current_thread() and not t.daemon:
                t.join()
        atexit._run_exitfuncs()
    except KeyboardInterrupt:
        print("vtable: interrupted", file=sys.stderr)
        code = 130
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe: nothing more to say there
            pass
    os._exit(code)


if __name__ == "__main__":
    run()
