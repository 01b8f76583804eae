"""The warm process's verb (`vtable.warm`)."""

from __future__ import annotations

from vtable.warm import WarmProcess


def warm(stop: bool = False) -> WarmProcess:
    """This environment's warm process (the one `vtable diagnose` hands its commands to):
    whether one runs, its pid, socket and log; `stop` asks it to end (it ends once the
    commands it runs have)."""
    return WarmProcess.of(stop)
