"""Channels fit for identification: present, complete, finite, and not zero or constant
(a table without pitch writes pitch channels of zeros; a ratio over such a channel is
0/0). Each failure is one line naming the run and the channel."""

from __future__ import annotations

import numpy as np

from vtable.errors import VtableError
from vtable.runs.model import Run


def channel_problem(run: Run, name: str) -> str | None:
    """Why `name` cannot be used (absent, missing samples, non-finite, all zero,
    constant), or None."""
    if not run.has(name):
        return f"no channel {name}"
    if run.missing.get(name):
        return f"{name} has {run.missing[name]} missing samples"
    x = run.channels[name]
    if not np.all(np.isfinite(x)):
        return f"{name} has non-finite samples"
    if not np.any(x):
        return f"{name} is zero throughout"
    if np.ptp(x) == 0:
        return f"{name} is constant ({x[0]:.4g} SI) throughout"
    if float(np.mean(np.square(x - x.mean()))) < np.finfo(float).tiny:
        return (f"{name} drives nothing: it varies by {np.ptp(x):.3g} SI, too little for its "
                "power to be a number (a spectrum over it would be infinite)")
    return None


def usable(run: Run, *names: str) -> bool:
    return all(channel_problem(run, n) is None for n in names)


def require(run: Run, *names: str, purpose: str = "") -> list[np.ndarray]:
    """The channels (SI), or a VtableError naming the first that cannot be used and what
    needs it."""
    out = []
    for n in names:
        why = channel_problem(run, n)
        if why:
            raise VtableError(f"{run.name}: {why}" + (f"; {purpose} needs it" if purpose
                                                      else ""))
        out.append(run.channels[n])
    return out


def require_any(run: Run, names: tuple[str, ...], purpose: str = "") -> list[np.ndarray]:
    """The usable channels among `names` (at least one), else one line listing why."""
    ok = [run.channels[n] for n in names if channel_problem(run, n) is None]
    if not ok:
        why = "; ".join(channel_problem(run, n) or "" for n in names)
        raise VtableError(f"{run.name}: {why}" + (f"; {purpose} needs one of "
                                                  f"{', '.join(names)}" if purpose else ""))
    return ok
