"""`python -m vtable` and the `vtable` command: the CLI, with an interrupt during start-up
(while the libraries load) ending as quietly as one during a command."""

from __future__ import annotations

import signal
import sys

from vtable.errors import on_sigint


def _quiet_interrupts(u) -> None:
    """An interrupt Python cannot raise (in an import's lock callback) is not printed as a
    traceback: `on_sigint` has remembered it, and the command ends on it in one line."""
    if not isinstance(u.exc_value, KeyboardInterrupt):
        sys.__unraisablehook__(u)


def run() -> None:
    signal.signal(signal.SIGINT, on_sigint)  # first: an interrupt while loading is seen
    sys.unraisablehook = _quiet_interrupts
    try:
        from vtable.cli import main  # in the try: Ctrl-C while the libraries load
    except KeyboardInterrupt:
        print("vtable: interrupted", file=sys.stderr)
        sys.exit(130)
    sys.exit(main())


if __name__ == "__main__":
    run()
