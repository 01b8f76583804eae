"""Running a user's Python file (`--effects-from`, `--controller-from`): the one loader the
effect registry and the controller kinds share."""

from __future__ import annotations

import hashlib
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

from vtable.errors import VtableError


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
