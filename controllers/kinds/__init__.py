"""Controller kinds (`ControllerKind`): the catalog's — ``three_variable`` (the report's),
``pid`` and ``tvc`` (one file each) — and a lab's own, registered from its file
(`load_file`: plain Python calling `register`)."""

from __future__ import annotations

from pathlib import Path

from vtable.controllers.kinds.base import ControllerKind, ControlUse
from vtable.errors import VtableError
from vtable.userfile import Registry

BUILT_IN = ("three_variable", "pid", "tvc")


def _check(kind: ControllerKind, where: str) -> None:
    if not isinstance(kind, ControllerKind):
        raise VtableError(f"register() takes a ControllerKind, got {type(kind).__name__}")


KINDS: Registry[ControllerKind] = Registry(
    BUILT_IN, "vtable.controllers.kinds.{}", "KIND", prefix="vtable_user_controller_",
    flag="--controller-from", check=_check,
    unknown=lambda name, known: (f"controller kind {name!r} is not known; expected one of "
                                 f"{', '.join(known)} (a lab's own: --controller-from FILE)"))


def register(kind: ControllerKind) -> ControllerKind:
    """Add a lab's controller kind; a name the catalog has is refused."""
    _check(kind, "register()")
    if kind.name in BUILT_IN:
        raise VtableError(f"controller kind {kind.name!r} is the catalog's; name yours "
                          "another way")
    return KINDS.add(kind.name, kind, KINDS.loading_file or "register()")


def names() -> list[str]:
    return KINDS.names()


def get(name: str) -> ControllerKind:
    return KINDS.get(name)


def load_file(path: str | Path) -> list[str]:
    """Run a lab's controller file (it calls `register`); returns the kinds it registered.
    Any problem is one line naming the file (`vtable.userfile.run_user_file`)."""
    return KINDS.load_file(path, "registers no controller kind (call "
                                 "vtable.controllers.kinds.register(...))")


def loaded(path: str | Path) -> bool:
    """Whether this process has loaded the file at `path` (`load_file`)."""
    return KINDS.loaded(path)


def source_file(name: str) -> str | None:
    """The file a lab's kind was loaded from (`load_file`); None for the catalog's and for
    one registered from code (another process cannot load it again)."""
    return KINDS.source_file(name)


__all__ = ["BUILT_IN", "KINDS", "ControlUse", "ControllerKind", "get", "load_file", "loaded",
           "names", "register", "source_file"]
