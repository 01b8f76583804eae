"""Where numba keeps vtable's compiled kernels, and how processes share their compiling.

Every module that compiles a kernel takes numba's ``njit`` from here
(``from vtable._numba import njit``), so the cache folder is worked out once, when a
kernel module is first imported, and not by ``import vtable``.
numba reads ``NUMBA_CACHE_DIR`` from the environment when it is first imported; when
numba was imported earlier (by the user, or by another package) its ``config.CACHE_DIR``
is set instead. A kernel decorated afterwards caches there.

A kernel's first call in a process goes through `first_compile`: processes that meet it at
the same moment (a diagnosis's workers) compile it once, the others waiting and then
loading it from the cache.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import os
import sys
import tempfile
from collections.abc import Iterator

try:
    import fcntl
except ImportError:  # Windows has no fcntl: no lock (`first_compile`)
    fcntl = None

from vtable import __version__


def cache_dir() -> str:
    """The folder for the compiled kernels: never inside the installed package (a leftover
    ``__pycache__`` there shadows a later editable install). The user's
    ``NUMBA_CACHE_DIR`` wins; else ``$XDG_CACHE_HOME/vtable/numba/<stamp>``
    (``~/.cache/...``), or a per-user folder in the temporary directory when the home is
    not writable; "" when neither is writable (numba's own default then)."""
    given = os.environ.get("NUMBA_CACHE_DIR")
    if given:
        return given
    home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    uid = os.getuid() if hasattr(os, "getuid") else 0
    for d in (os.path.join(home, "vtable", "numba"),
              os.path.join(tempfile.gettempdir(), f"vtable-numba-{uid}")):
        d = os.path.join(d, sources_stamp())
        try:
            os.makedirs(d, exist_ok=True)
            if os.access(d, os.W_OK):
                return d
        except OSError:
            continue
    return ""


def sources_stamp() -> str:
    """A stamp of the package's kernel sources (every module holding ``njit``) and of
    numba's release: numba checks a cached kernel against its own file only, not the
    kernels it calls from other modules (the servo law of `vtable.hydraulics` inside the
    reduced model's kernel), so a changed kernel source gets a fresh cache folder; and a
    new numba gets one too, where its index of an older numba's kernels would be stale
    (`first_compile` takes no lock for a kernel whose index exists)."""
    root = os.path.dirname(os.path.abspath(__file__))
    h = hashlib.sha256(__version__.encode() + _numba_release())
    for dirpath, dirnames, files in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if d != "__pycache__")
        for f in sorted(files):
            if f.endswith(".py"):
                with open(os.path.join(dirpath, f), "rb") as fh:
                    text = fh.read()
                if b"njit" in text:
                    h.update(f"{dirpath[len(root):]}/{f}".encode() + text)
    return h.hexdigest()[:12]


def _numba_release() -> bytes:
    """numba's version file, read, not imported (numba reads ``NUMBA_CACHE_DIR`` when it
    is imported); empty where it cannot be read."""
    try:
        spec = importlib.util.find_spec("numba")
        with open(os.path.join(os.path.dirname(spec.origin), "_version.py"), "rb") as fh:
            return fh.read()
    except (AttributeError, TypeError, ImportError, OSError):
        return b""


CACHE_DIR = cache_dir()
if CACHE_DIR:
    os.environ["NUMBA_CACHE_DIR"] = CACHE_DIR  # read by numba's first import, and workers
    if "numba" in sys.modules:  # numba read its configuration already
        sys.modules["numba"].config.CACHE_DIR = CACHE_DIR

import numba  # noqa: E402  (after NUMBA_CACHE_DIR is set)
from numba import njit  # noqa: E402


def _lock_path(kernel) -> str:
    """The lock file of `kernel` (a dispatcher): named after its module and function, in
    numba's cache folder as it is now (or the temporary directory)."""
    d = os.path.join(numba.config.CACHE_DIR or tempfile.gettempdir(), "locks")
    os.makedirs(d, exist_ok=True)
    f = getattr(kernel, "py_func", kernel)
    return os.path.join(d, f"{f.__module__}.{f.__qualname__}.lock")


def _cached(kernel) -> bool:
    """Whether numba's cache holds an index for `kernel` (a process compiled it before):
    a process loads it then, and needs no lock. Without that attribute (another numba),
    as if not."""
    try:
        return os.path.exists(kernel._cache._cache_file._index_path)
    except (AttributeError, TypeError):
        return False


@contextlib.contextmanager
def first_compile(kernel) -> Iterator[None]:
    """Around a call of `kernel` (a dispatcher cached on disk, ``cache=True``): its first
    call in this process, should another process (or thread) be compiling it, waits until
    that one's first call has returned and then loads what it cached; the first to come
    holds a lock on the kernel's name (`fcntl.flock`) through its call, while numba
    compiles (or loads) it. A diagnosis's workers meet the same kernels at the same
    moments and each compiled them, a second or more each (a README campaign's first
    diagnosis compiled five twice). A kernel this process has compiled or loaded (or a
    plain function: numba's JIT off), a system without `flock` or a folder that refuses
    locks takes no lock; nor does one numba's cache holds already (`_cached`): every
    process loads it at once (a warm diagnosis's two workers loaded their first kernels
    one after the other, the second waiting 0.2-0.3 s on the first's lock; one cached for
    other argument types only is then compiled without the lock, by each process that
    meets it; a new numba's cache is a folder of its own, `sources_stamp`). Not nested: a
    kernel called inside another's block would wait for itself."""
    fh = None
    # whether it has compiled or loaded one: its `overloads`, not `signatures` (which lists
    # them, hashing every type of every argument: 4 µs, three times a simulation)
    if fcntl is not None and not getattr(kernel, "overloads", True) and not _cached(kernel):
        try:
            fh = open(_lock_path(kernel), "a")  # closed below
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:  # another is compiling it: wait, then load it
                fcntl.flock(fh, fcntl.LOCK_SH)
                fcntl.flock(fh, fcntl.LOCK_UN)
                fh.close()
                fh = None
        except OSError:  # no lock here (a file system without locks): as without flock
            if fh is not None:
                fh.close()
            fh = None
    if fh is None:
        yield
        return
    with fh:
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


__all__ = ["CACHE_DIR", "cache_dir", "first_compile", "njit", "sources_stamp"]
