"""A warm process's start (`vtable.warm`), before its libraries load: run by
`vtable.warm.client`'s boot line as ``boot(socket, vtable's folder, environment)``."""

from __future__ import annotations

import fcntl
import os
import sys
import time
from pathlib import Path

from vtable.warm import here, make_room


def boot(socket_path: str, vtable_folder: str, given: dict[str, str]) -> None:
    """A warm process's start (`vtable.warm.client` runs it with the caller's module search
    path and the collector off): its socket's lock taken (retried for a moment: `holder`
    looks at it with a shared lock), the vtable it imports checked to be its caller's,
    room made (`make_room`), and only then the libraries loaded and the commands answered
    (`vtable.warm.server.main`). A second process for the socket ends at once (0), one
    that would import another vtable says so and ends (3)."""
    path = Path(socket_path)
    lock = open(f"{path}.lock", "a+")  # held for the process's life
    for _ in range(50):
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            break
        except OSError:
            time.sleep(0.01)
    else:
        return  # another warm process has this socket
    if here() != vtable_folder:
        print(f"vtable at {here()} here, the caller's at {vtable_folder}: no warm process",
              file=sys.stderr)
        sys.exit(3)
    lock.truncate(0)
    lock.write(f"{os.getpid()}\n")
    lock.flush()
    make_room(path.parent)
    from vtable.warm.server import main  # the libraries, now that it is the one

    main(path, lock, given)
