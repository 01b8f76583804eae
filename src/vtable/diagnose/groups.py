"""Channel groups: which format channels are averaged into one scored signal, and what a
run leaves out of them.

A building's floors (`run_groups`). The run format's floorK_acc and floorK_disp are the
absolute x motion of floor K from the bottom; how many floors a run has is its [specimen]'s
storey count N (an SDOF frame is one storey). The top floor is the quantity the top-mass
instruments measure, so floorN_acc is one more sensor of "structure acceleration" and
floorN_disp of "structure displacement" (averaged with them as duplicate sensors are). Each
floor below the top is a group of its own, "floor K acceleration" and "floor K
displacement": different floors are different signals and are never averaged together,
and one group per floor keeps the campaign error what it was, a mean of per-group NRMS,
each floor weighing as much as the top. Floor channels above the declared N (the model has
no such floor) and every other channel no group holds are not scored; `campaign_notes` says
so, naming them.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from vtable.params.specimen import SDOFSpecimen, ShearBuilding
from vtable.runs.model import FORMAT_UNITS, Run

#: channel groups: name -> the format channels averaged into it (a run's floors are added by
#: `run_groups`)
GROUPS: dict[str, tuple[str, ...]] = {
    "table displacement": ("avg_hdisp", "h1_disp", "h2_disp", "h3_disp"),
    "table velocity": ("h_vel",),
    "table acceleration": ("avg_hacc",),
    "actuator force": ("h1_force", "h2_force", "h3_force"),
    "pitch": ("pitch_acc",),
    "structure acceleration": ("acc_n_ne", "acc_n_nw"),
    "structure displacement": ("pot_n_sw", "pot_n_se"),
}
#: the groups of a specimen's top mass (none for a rigid block or a bare table)
STRUCTURE = ("structure acceleration", "structure displacement")
_FLOOR_CHANNEL = re.compile(r"floor([1-9][0-9]*)_(acc|disp)")
_FLOOR_GROUP = re.compile(r"floor ([1-9][0-9]*) (acceleration|displacement)")


class _GroupUnits(dict):
    """GROUPS' units, and those of every floor group "floor K acceleration" (g) and
    "floor K displacement" (in) (`run_groups`; not listed when iterating)."""

    def __missing__(self, key: str) -> str:
        m = _FLOOR_GROUP.fullmatch(key) if isinstance(key, str) else None
        if m is None:
            raise KeyError(key)
        return "g" if m.group(2) == "acceleration" else "in"

    def __contains__(self, key: object) -> bool:
        return dict.__contains__(self, key) or (
            isinstance(key, str) and _FLOOR_GROUP.fullmatch(key) is not None)


#: the unit each group is shown in (the run format's unit of its channels)
GROUP_UNITS: dict[str, str] = _GroupUnits({g: FORMAT_UNITS[c[0]] for g, c in GROUPS.items()})


def short(name: str) -> str:
    return Path(name).name


_STOREYS: dict[str, int] = {}  # the [specimen] table's repr -> its storey count


def storeys(run: Run) -> int:
    """How many floors the run's declared [specimen] has: its storeys for a shear building,
    1 for an SDOF frame (its top mass), 0 for a rigid block or a bare table."""
    key = repr(run.meta.get("specimen"))
    if key not in _STOREYS:
        spec = run.specimen()
        _STOREYS[key] = (len(spec.weights) if isinstance(spec, ShearBuilding)
                         else 1 if isinstance(spec, SDOFSpecimen) else 0)
    return _STOREYS[key]


def run_groups(run: Run) -> dict[str, tuple[str, ...]]:
    """The channel groups of `run`: `GROUPS`, the top floor's channels added to the
    structure groups, and a group for each floor below the top (module docstring)."""
    n = storeys(run)
    groups = dict(GROUPS)
    if n:
        groups["structure acceleration"] += (f"floor{n}_acc",)
        groups["structure displacement"] += (f"floor{n}_disp",)
    else:  # a rigid block or a bare table: the model predicts no structure motion
        for g in STRUCTURE:
            del groups[g]
    for k in range(1, n):
        groups[f"floor {k} acceleration"] = (f"floor{k}_acc",)
        groups[f"floor {k} displacement"] = (f"floor{k}_disp",)
    return groups



def excluded_channels(run: Run) -> list[str]:
    """The group channels a run has that are left out of its groups (missing samples)."""
    out = []
    for g, chans in run_groups(run).items():
        for c in chans:
            if run.has(c) and run.missing.get(c):
                out.append(f"{run.name}: channel {c!r} has {run.missing[c]} missing samples; "
                           f"left out of {g}")
        present = [c for c in chans if run.has(c)]
        if present and group_signal(run, g) is None:
            why = ("every channel has missing samples" if all(run.missing.get(c) for c in present)
                   else "its channels are zero throughout")
            out.append(f"{run.name}: {g} is not scored ({why})")
    return out


def unscored_channels(run: Run) -> list[str]:
    """Notes naming every channel of `run` that no channel group holds (so it is not
    scored): floor channels above the declared storeys, then all others. The command
    h_span drives the model and is not listed."""
    grouped = {c for chans in run_groups(run).values() for c in chans}
    rest = [c for c in run.channels if c not in grouped and c != "h_span"]
    n = storeys(run)
    structure = {c for g in STRUCTURE for c in GROUPS[g]}
    floors = [c for c in rest if _FLOOR_CHANNEL.fullmatch(c) or c in structure]
    others = [c for c in rest if c not in floors]
    out = []
    if floors:
        why = ("the [specimen] has no storeys; the model predicts no structure motion"
               if n == 0 else
               "the [specimen] declares 1 storey; the model predicts floor 1 only" if n == 1
               else f"the [specimen] declares {n} storeys; the model predicts floors 1-{n}")
        out.append(f"{run.name}: left out: {', '.join(floors)} ({why})")
    if others:
        out.append(f"{run.name}: left out: {', '.join(others)} (not scored: no channel group "
                   "holds them)")
    return out


def campaign_notes(runs: list[Run]) -> list[str]:
    """What the readers reported (Run.reports), the resampling done and the channels left
    out (missing samples, no channel group), each naming its run."""
    notes = []
    for r in runs:
        for rep in r.reports:
            notes.append(rep if short(r.name) in rep else f"{r.name}: {rep}")
        notes += excluded_channels(r)
        notes += unscored_channels(r)
    return list(dict.fromkeys(notes))


def group_signal(run: Run, group: str) -> np.ndarray | None:
    """The measured signal of a group of `run_groups(run)` (its channels without missing
    samples averaged); None when it has none or they are zero throughout."""
    chans = [c for c in run_groups(run).get(group, ()) if run.has(c) and not run.missing.get(c)]
    if not chans:
        return None
    y = np.mean([run.channels[c] for c in chans], axis=0)
    return y if np.sqrt(np.mean(y**2)) > 0 else None


def group_prediction(pred: dict[str, np.ndarray], run: Run, group: str) -> np.ndarray | None:
    """The model's prediction of a group: its channels averaged as `group_signal` averages
    the measured ones (one array predicted for several sensors counts once per sensor)."""
    chans = [c for c in run_groups(run).get(group, ())
             if run.has(c) and not run.missing.get(c) and c in pred]
    if not chans:
        return None
    arrays = [pred[c] for c in chans]
    first = arrays[0]
    if all(a is first for a in arrays):  # the lumped model predicts one for all
        return first
    return np.mean(arrays, axis=0)

