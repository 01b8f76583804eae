"""Where numba keeps vtable's compiled kernels.

Every module that compiles a kernel takes numba's ``njit`` from here
(``from vtable._numba import njit``), so the cache folder is worked out once, when a
kernel module is first imported, and not by ``import vtable``.
numba reads ``NUMBA_CACHE_DIR`` from the environment when it is first imported; when
numba was imported earlier (by the user, or by another package) its ``config.CACHE_DIR``
is set instead. A kernel decorated afterwards caches there.
"""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile

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
    """A stamp of the package's kernel sources (every module holding ``njit``): numba
    checks a cached kernel against its own file only, not the kernels it calls from other
    modules (the servo law of `vtable.hydraulics` inside the reduced model's kernel), so a
    changed kernel source gets a fresh cache folder."""
    root = os.path.dirname(os.path.abspath(__file__))
    h = hashlib.sha256(__version__.encode())
    for dirpath, dirnames, files in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if d != "__pycache__")
        for f in sorted(files):
            if f.endswith(".py"):
                with open(os.path.join(dirpath, f), "rb") as fh:
                    text = fh.read()
                if b"njit" in text:
                    h.update(f"{dirpath[len(root):]}/{f}".encode() + text)
    return h.hexdigest()[:12]


CACHE_DIR = cache_dir()
if CACHE_DIR:
    os.environ["NUMBA_CACHE_DIR"] = CACHE_DIR  # read by numba's first import, and workers
    if "numba" in sys.modules:  # numba read its configuration already
        sys.modules["numba"].config.CACHE_DIR = CACHE_DIR

from numba import njit  # noqa: E402  (after NUMBA_CACHE_DIR is set)

__all__ = ["CACHE_DIR", "cache_dir", "njit", "sources_stamp"]
