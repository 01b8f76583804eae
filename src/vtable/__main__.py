"""`python -m vtable` and the `vtable` command: the CLI, with an interrupt during start-up
(while the libraries load) ending as quietly as one during a command."""

from __future__ import annotations

import sys


def run() -> None:
    try:
        from vtable.cli import main  # in the try: Ctrl-C while the libraries load
    except KeyboardInterrupt:
        print("vtable: interrupted", file=sys.stderr)
        sys.exit(130)
    sys.exit(main())


if __name__ == "__main__":
    run()
