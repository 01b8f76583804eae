"""vtable: a physics-based virtual shaking table after report UCB/EERC-91/13."""

import os as _os
import sys as _sys

__version__ = "0.1.0"


def _numba_cache_dir() -> str:
    """Where numba keeps vtable's compiled kernels: never inside the installed package
    (a leftover ``__pycache__`` there shadows a later editable install). The user's
    ``NUMBA_CACHE_DIR`` wins; else ``$XDG_CACHE_HOME/vtable/numba`` (``~/.cache/...``),
    or a per-user folder in the temporary directory when the home is not writable."""
    given = _os.environ.get("NUMBA_CACHE_DIR")
    if given:
        return given
    import tempfile

    home = _os.environ.get("XDG_CACHE_HOME") or _os.path.join(_os.path.expanduser("~"),
                                                               ".cache")
    for base in (home, tempfile.gettempdir()):
        d = _os.path.join(base, "vtable", "numba") if base == home else \
            _os.path.join(base, f"vtable-numba-{_os.getuid() if hasattr(_os, 'getuid') else 0}")
        d = _os.path.join(d, _sources_stamp())
        try:
            _os.makedirs(d, exist_ok=True)
            if _os.access(d, _os.W_OK):
                return d
        except OSError:
            continue
    return ""


def _sources_stamp() -> str:
    """A stamp of the package's numba kernels' sources: numba checks a cached kernel against
    its own file only, not the kernels it calls from other modules (the servo law in
    `vtable.hydraulics` inside the reduced model's kernel), so a changed kernel source gets
    a fresh cache folder."""
    import hashlib

    root = _os.path.dirname(_os.path.abspath(__file__))
    h = hashlib.sha256(__version__.encode())
    for dirpath, dirnames, files in _os.walk(root):
        dirnames[:] = sorted(d for d in dirnames if d != "__pycache__")
        for f in sorted(files):
            if f.endswith(".py"):
                with open(_os.path.join(dirpath, f), "rb") as fh:
                    text = fh.read()
                if b"njit" in text:
                    h.update(f"{dirpath[len(root):]}/{f}".encode() + text)
    return h.hexdigest()[:12]


_cache = _numba_cache_dir()
if _cache:
    _os.environ["NUMBA_CACHE_DIR"] = _cache
    if "numba" in _sys.modules:  # numba read its configuration already
        _sys.modules["numba"].config.CACHE_DIR = _cache
