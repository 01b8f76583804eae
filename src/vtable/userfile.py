"""Running a user's Python file (`--effects-from`, `--controller-from`), and the one
registry shape (`Registry`) the effects and the controller kinds share."""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Generic, TypeVar

from vtable.errors import VtableError

T = TypeVar("T")


def run_user_file(path: str | Path, prefix: str, flag: str) -> Path:
    """`user_module`'s file, resolved (the file is run for what it registers)."""
    return Path(user_module(path, prefix, flag).__file__).resolve()


def user_module(path: str | Path, prefix: str, flag: str) -> ModuleType:
    """Run `path` as the module `prefix` + a hash of its resolved path (the same name in
    every process: a compiled stage refers to its module). Any problem — a missing file,
    a syntax error, an exception while it runs — is one line naming the file (`flag`, the
    option that names such files, in the missing-file message). Returns the module.
    """
    p = Path(path)
    if not p.is_file():
        raise VtableError(f"{p}: no such file ({flag})")
    modname = prefix + hashlib.sha256(str(p.resolve()).encode()).hexdigest()[:16]
    spec = importlib.util.spec_from_file_location(modname, p)
    if spec is None or spec.loader is None:
        raise VtableError(f"{p}: cannot be loaded as a Python file")
    module = importlib.util.module_from_spec(spec)
    try:
        sys.modules[modname] = module
        spec.loader.exec_module(module)
    except VtableError as e:
        raise VtableError(str(e) if str(p) in str(e) else f"{p}: {e}") from None
    except SyntaxError as e:
        raise VtableError(f"{p}: line {e.lineno}: syntax error: {e.msg}") from None
    except Exception as e:
        raise VtableError(f"{p}: {type(e).__name__} while loading: {e}") from None
    return module


class Registry(Generic[T]):
    """Named entries of one kind, the one shape of vtable's registries (effects,
    controller kinds): the catalog's (`built_in`, each the attribute `attr` of the module
    `module.format(name)`, loaded on first use) and a user's, registered from code
    (`add`) or from a file that calls its registry's `register` (`load_file`).

    `check(entry, where)` vets every entry (the catalog's too); `unknown(name, names)` is
    the message for a name nobody registered."""

    def __init__(self, built_in: tuple[str, ...], module: str, attr: str, *,
                 prefix: str, flag: str, check: Callable[[T, str], None],
                 unknown: Callable[[str, list[str]], str]) -> None:
        self.built_in = tuple(built_in)
        self._module, self._attr = module, attr
        self._prefix, self._flag = prefix, flag
        self._check, self._unknown = check, unknown
        self._entries: dict[str, T] = {}
        self._user: set[str] = set()
        self._files: dict[str, str] = {}  # a user's entry -> the file that registered it
        self._loading: list[str] | None = None  # names registered while a file loads
        self.loading_file: str | None = None  # that file (for messages)
        self._ready = False

    def _load(self) -> None:
        if not self._ready:
            self._ready = True
            for name in self.built_in:
                where = self._module.format(name)
                entry = getattr(importlib.import_module(where), self._attr)
                self._check(entry, where)
                self._entries[name] = entry

    def add(self, name: str, entry: T, where: str) -> T:
        """A user's entry (`check`ed; registering a name again replaces it)."""
        self._load()
        self._check(entry, where)
        self._entries[name] = entry
        self._user.add(name)
        self._files.pop(name, None)  # load_file records it again when it is loading one
        if self._loading is not None:
            self._loading.append(name)
        return entry

    def get(self, name: str) -> T:
        self._load()
        if name not in self._entries:
            raise VtableError(self._unknown(name, list(self._entries)))
        return self._entries[name]

    def names(self) -> list[str]:
        """Every registered name: the catalog's, then users'."""
        self._load()
        return list(self._entries)

    def is_user(self, name: str) -> bool:
        return name in self._user

    def load_file(self, path: str | Path, none: str) -> list[str]:
        """Run a user's file (`run_user_file`); the names it registered, in order. One
        that registers nothing is the one-line error `none`."""
        p = Path(path)
        self._load()
        self._loading, self.loading_file = [], str(p)
        try:
            resolved = run_user_file(p, self._prefix, self._flag)
        finally:
            added = list(dict.fromkeys(self._loading))
            self._loading, self.loading_file = None, None
        if not added:
            raise VtableError(f"{p}: {none}")
        for name in added:
            self._files[name] = str(resolved)
        return added

    def loaded(self, path: str | Path) -> bool:
        """Whether this process has loaded the file at `path` (`load_file`)."""
        return str(Path(path).resolve()) in set(self._files.values())

    def source_file(self, name: str) -> str | None:
        """The file a user's entry was loaded from (`load_file`); None for the catalog's
        and for one registered from code (another process cannot load it again)."""
        return self._files.get(name)

    def snapshot(self) -> tuple:
        """The registry's state (`restore` puts it back: tests that register their own)."""
        self._load()
        return dict(self._entries), set(self._user), dict(self._files)

    def restore(self, state: tuple) -> None:
        for live, saved in zip((self._entries, self._user, self._files), state, strict=True):
            live.clear()
            live.update(saved)

    def remove(self, name: str) -> T:
        """Take a user's entry out (a run that names it then reads as unknown)."""
        self._user.discard(name)
        self._files.pop(name, None)
        return self._entries.pop(name)
