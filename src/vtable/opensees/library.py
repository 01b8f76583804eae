"""Importing openseespy, an optional extra (``pip install "vtable[opensees]"``).

The Linux wheel (``openseespylinux``) bundles its BLAS, LAPACK and Fortran runtime in a
``lib`` folder beside its extension but does not tell the loader where: on a machine
without system BLAS the import fails with only "Failed to import openseespy on Linux".
`opensees` loads the bundled libraries first (globally, so the extension finds them), then
imports; the install alone is then enough.
"""

from __future__ import annotations

import atexit
import ctypes
import functools
import importlib.util
import os
import sys
import tempfile
from pathlib import Path
from types import ModuleType

from vtable.errors import VtableError

INSTALL = 'pip install "vtable[opensees]"'
#: the bundled libraries, in load order (each needs the ones before it)
_BUNDLED = ("libquadmath.so.0", "libgfortran.so.4", "libgfortran.so.5", "libgomp.so.1",
            "libblas.so.3", "liblapack.so.3")


def _preload_bundled() -> None:
    """Load the Linux wheel's bundled libraries, if it has them (a no-op elsewhere)."""
    if not sys.platform.startswith("linux"):
        return
    spec = importlib.util.find_spec("openseespylinux")
    if spec is None or not spec.submodule_search_locations:
        return
    lib = Path(next(iter(spec.submodule_search_locations))) / "lib"
    for name in _BUNDLED:
        f = lib / name
        if f.is_file():
            try:
                ctypes.CDLL(os.fspath(f), mode=ctypes.RTLD_GLOBAL)
            except OSError:
                pass  # the system's own copy may do; the import below says if not


@functools.cache
def opensees() -> ModuleType:
    """``openseespy.opensees``, or a one-line error saying how to install it."""
    if importlib.util.find_spec("openseespy") is None:
        raise VtableError(f"an OpenSees specimen needs openseespy: {INSTALL}")
    _preload_bundled()
    try:
        import openseespy.opensees as ops
    except (ImportError, RuntimeError, OSError) as e:
        raise VtableError(f"openseespy is installed but does not load ({e}); reinstall it "
                          f"with {INSTALL}") from None
    atexit.register(_quiet_exit)
    ops.logFile(os.fspath(log_path()), "-noEcho")  # its chatter kept for our messages
    return ops


@functools.cache
def log_path() -> Path:
    """Where this process's OpenSees writes its messages (not to the terminal)."""
    fd, name = tempfile.mkstemp(prefix="vtable-opensees-", suffix=".log")
    os.close(fd)
    atexit.register(lambda: Path(name).unlink(missing_ok=True))
    return Path(name)


def last_message() -> str:
    """OpenSees' last warning or error line, for our one-line messages ("" if none)."""
    try:
        lines = [ln.strip() for ln in log_path().read_text(errors="replace").splitlines()]
    except OSError:
        return ""
    lines = [ln for ln in lines if ln and "VERY SLOW" not in ln]
    return lines[-1] if lines else ""


def _quiet_exit() -> None:
    """OpenSees writes "Process 0 Terminating" to stderr from a destructor after Python
    has finished; point stderr at /dev/null once Python's own exit work is done."""
    try:
        sys.stderr.flush()
        os.dup2(os.open(os.devnull, os.O_WRONLY), 2)
    except OSError:
        pass


def explain(e: Exception) -> str:
    """An exception's text, OpenSees' own message in place of its "See log file"."""
    text = str(e)
    if text.startswith("See "):
        return last_message() or text
    return text
