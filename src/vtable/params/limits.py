"""The table's performance limits as a law, written once: a motion against the stroke and
velocity of Table 2.2 (or a run's [table]), a force against the actuators' capacity
(Table 2.1), a signal's content against the table's band. `vtable.sim` checks commands
with it before a run, `vtable.drive` checks a drive; both name the limit and the first
time it is passed, in the table's units (`vtable.display`)."""

from __future__ import annotations

import numpy as np
import scipy.signal

from vtable import display
from vtable.errors import VtableError


def _first_beyond(t: np.ndarray, x: np.ndarray, limit: float) -> tuple[float, float] | None:
    """(peak |x|, first time |x| > limit), or None when x stays within ±limit."""
    over = np.abs(x) > limit * (1 + 1e-9)
    if not over.any():
        return None
    return float(np.max(np.abs(x))), float(t[int(np.argmax(over))])


def motion_limits(vt, dof: str = "x") -> dict[str, tuple[float, str]]:
    """The stroke and velocity limits of `dof` ("x" horizontal, "z" vertical) the table
    has: name -> (SI value, report unit); a limit it does not declare is left out."""
    s = vt.table.specs
    pairs = ({"stroke": (s.stroke_h, "in"), "velocity limit": (s.velocity_h, "in/s")}
             if dof == "x" else
             {"stroke": (s.stroke_v, "in"), "velocity limit": (s.velocity_v, "in/s")})
    return {k: v for k, v in pairs.items() if v[0] is not None}


def check_motion(vt, t: np.ndarray, x: np.ndarray, what: str = "x command",
                 dof: str = "x") -> None:
    """Refuse a displacement history `x` (m) beyond the table's stroke or velocity for
    `dof`, naming `what`, the peak, the limit and the first time it is passed."""
    fam = display.table_family(vt)
    v = np.gradient(x, t) if len(t) > 1 else np.zeros_like(x)
    limits = motion_limits(vt, dof)
    for name, y in (("stroke", x), ("velocity limit", v)):
        if name not in limits:
            continue
        lim, unit = limits[name]
        hit = _first_beyond(t, y, lim)
        if hit is not None:
            label = what if name == "stroke" else f"{what} velocity"
            raise VtableError(
                f"{label} reaches {display.quantity(hit[0], unit, fam, '.2f' if y is x else '.1f')}"
                f" (first beyond "
                f"±{display.quantity(lim, unit, fam, 'g')} at t = {hit[1]:.3f} s), the "
                f"table's {name} ({vt.limits_source})")


def check_force(vt, t: np.ndarray, force: np.ndarray, what: str = "actuator force",
                group: str = "horizontal") -> None:
    """Refuse a force per actuator of `group` (N) beyond the smallest capacity among them
    (Table 2.1)."""
    acts = vt.group(group)
    if not acts:
        return
    lim = min(a.capacity for a in acts)
    hit = _first_beyond(t, force, lim)
    if hit is not None:
        fam = display.table_family(vt)
        raise VtableError(
            f"{what} reaches {display.quantity(hit[0], 'kip', fam, '.3g')} (first beyond "
            f"±{display.quantity(lim, 'kip', fam, 'g')} at t = {hit[1]:.3f} s), the "
            f"{group} actuators' capacity ({vt.limits_source})")


def share_above(x: np.ndarray, fs: float, f_hz: float) -> float:
    """The share of the RMS of x's acceleration (its second difference) above `f_hz`: the
    part of a motion a table whose band ends at `f_hz` does not reproduce."""
    if f_hz >= fs / 2:
        return 0.0
    a = np.diff(x, 2)
    sos = scipy.signal.butter(6, f_hz, "highpass", fs=fs, output="sos")
    rms = float(np.sqrt(np.mean(a**2)))
    return 0.0 if rms == 0 else float(np.sqrt(np.mean(scipy.signal.sosfiltfilt(sos, a)**2))
                                      / rms)
