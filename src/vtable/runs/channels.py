"""The interchange format's channels and their file units
(docs/run-format.md)."""

from __future__ import annotations

import re
from typing import Any

from vtable import units

_FLOOR = re.compile(r"floor([1-9][0-9]*)_(acc|disp|drift|shear)")
_FLOOR_UNITS = {"acc": "g", "disp": "in", "drift": "in", "shear": "kip"}


class _FormatUnits(dict):
    """The format's channel -> unit table. Besides the fixed names it holds the floor
    channels floorK_acc (g), floorK_disp (in), floorK_drift (in) and floorK_shear (kip)
    for any K >= 1 (they are not listed when iterating)."""

    def __missing__(self, key: str) -> str:
        m = _FLOOR.fullmatch(key) if isinstance(key, str) else None
        if m is None:
            raise KeyError(key)
        return _FLOOR_UNITS[m.group(2)]

    def __contains__(self, key: object) -> bool:
        return dict.__contains__(self, key) or (
            isinstance(key, str) and _FLOOR.fullmatch(key) is not None)

    def get(self, key: str, default: Any = None) -> Any:
        return self[key] if key in self else default


#: the interchange format's channels and units (docs/run-format.md)
FORMAT_UNITS: dict[str, str] = _FormatUnits({
    "h_span": "in", "avg_hdisp": "in", "avg_vdisp": "in", "avg_hacc": "g", "avg_vacc": "g",
    "pitch_acc": "rad/s2", "roll_acc": "rad/s2", "twist_acc": "rad/s2", "pitch_disp": "rad",
    **{f"v{i}_disp": "in" for i in range(1, 5)}, **{f"h{i}_disp": "in" for i in range(1, 4)},
    **{f"h{i}_force": "kip" for i in range(1, 4)}, **{f"v{i}_force": "kip" for i in range(1, 5)},
    **{f"p{i}_stab": "kip" for i in range(1, 5)}, "h_vel": "in/s",
    "acc_n_ne": "g", "acc_n_nw": "g", "acc_w_nw": "g", "acc_w_sw": "g",
    "pot_n_sw": "in", "pot_n_se": "in", "acc_cmd": "g",
})
#: channels the controller generates: constant, they drive nothing
COMMAND_CHANNELS = ("h_span", "acc_cmd")


def channel_dimension(name: str) -> str | None:
    """The dimension of a format channel (length, acceleration, force, angle, ...); None
    for a channel the format does not name (an extra channel takes any unit)."""
    unit = FORMAT_UNITS.get(name)
    return None if unit is None else units.dimension(unit)
