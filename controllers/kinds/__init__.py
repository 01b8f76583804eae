"""Controller kinds (`ControllerKind`): the catalog's — ``three_variable`` (the report's),
``pid`` and ``tvc`` (one file each) — and a lab's own, registered from its file
(`load_file`: plain Python calling `register`)."""

from __future__ import annotations

import importlib
from pathlib import Path

from vtable.controllers.kinds.base import ControllerKind, ControlUse
from vtable.errors import VtableError
from vtable.userfile import run_user_file

BUILT_IN = ("three_variable", "pid", "tvc")
_REGISTRY: dict[str, ControllerKind] = {}
_FILES: dict[str, str] = {}  # a lab's kind -> the file that registered it


def _load_built_in() -> None:
    if not _REGISTRY:
        for name in BUILT_IN:
            _REGISTRY[name] = importlib.import_module(f"vtable.controllers.kinds.{name}").KIND


def register(kind: ControllerKind) -> ControllerKind:
    """Add a lab's controller kind; a name the catalog has is refused."""
    _load_built_in()
    if not isinstance(kind, ControllerKind):
        raise VtableError(f"register() takes a ControllerKind, got {type(kind).__name__}")
    if kind.name in BUILT_IN:
        raise VtableError(f"controller kind {kind.name!r} is the catalog's; name yours "
                          "another way")
    _REGISTRY[kind.name] = kind
    _FILES.pop(kind.name, None)  # load_file records it again when it is loading one
    _LOADING.append(kind.name)
    return kind


_LOADING: list[str] = []  # the kinds registered while a file loads (load_file)


def names() -> list[str]:
    _load_built_in()
    return list(_REGISTRY)


def get(name: str) -> ControllerKind:
    _load_built_in()
    if name not in _REGISTRY:
        raise VtableError(f"controller kind {name!r} is not known; expected one of "
                          f"{', '.join(_REGISTRY)} (a lab's own: --controller-from FILE)")
    return _REGISTRY[name]


def load_file(path: str | Path) -> list[str]:
    """Run a lab's controller file (it calls `register`); returns the kinds it registered.
    Any problem is one line naming the file (`vtable.userfile.run_user_file`)."""
    p = Path(path)
    _load_built_in()
    _LOADING.clear()
    try:
        resolved = run_user_file(p, "vtable_user_controller_", "--controller-from")
    finally:
        added = list(dict.fromkeys(_LOADING))
        _LOADING.clear()
    if not added:
        raise VtableError(f"{p}: registers no controller kind (call "
                          "vtable.controllers.kinds.register(...))")
    for n in added:
        _FILES[n] = str(resolved)
    return added


def loaded(path: str | Path) -> bool:
    """Whether this process has loaded the file at `path` (`load_file`)."""
    return str(Path(path).resolve()) in set(_FILES.values())


def source_file(name: str) -> str | None:
    """The file a lab's kind was loaded from (`load_file`); None for the catalog's and for
    one registered from code (another process cannot load it again)."""
    return _FILES.get(name)


__all__ = ["BUILT_IN", "ControlUse", "ControllerKind", "get", "load_file", "names", "register",
           "source_file"]
