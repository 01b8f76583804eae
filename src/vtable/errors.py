"""The one exception type users see: a one-line message naming what was wrong."""

import difflib


class VtableError(Exception):
    """Bad input or an impossible request; the message is a single line for the user."""


class UnstableError(VtableError):
    """A configuration whose closed loop is unstable (eigenvalues with positive real part)."""

    def __init__(self, what: str, eigenvalues) -> None:
        self.eigenvalues = list(eigenvalues)
        roots = ", ".join(_fmt_root(z) for z in self.eigenvalues)
        super().__init__(f"{what} is unstable: eigenvalues with positive real part {roots} (1/s)")


def _fmt_root(z: complex) -> str:
    z = complex(z)
    if abs(z.imag) < 1e-12 * max(1.0, abs(z)):
        return f"{z.real:.4g}"
    return f"{z.real:.4g}{z.imag:+.4g}j"


def did_you_mean(name: object, candidates) -> str:
    """" (did you mean 'x'?)" when `name` is a near miss of one of `candidates` (difflib's
    ratio ≥ 0.6, the closest), else ""."""
    close = difflib.get_close_matches(str(name), [str(c) for c in candidates], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def interrupted(e: BaseException | None) -> bool:
    """Whether `e` is a KeyboardInterrupt or was raised because one was pending (code
    numba compiled, or numba compiling, returns a SystemError chained to the interrupt):
    a handler that catches Exception must raise it again, or Ctrl-C is lost."""
    seen = set()
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False


#: whether Ctrl-C reached this process (`on_sigint`): an interrupt Python swallows (one
#: raised inside an import's lock callback is printed "Exception ignored" and dropped) is
#: still seen, by the progress bar and at the command's end
_SIGINT = [False]


def on_sigint(signum, frame) -> None:
    """The CLI's SIGINT handler: Python's own (raise KeyboardInterrupt), remembered."""
    _SIGINT[0] = True
    raise KeyboardInterrupt


def sigint_seen() -> bool:
    """Whether `on_sigint` has run in this process."""
    return _SIGINT[0]
