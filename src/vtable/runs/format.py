"""Runs in the interchange format (shared/spec/measurement-format.md, version 1):
RUN.csv (time + channels) and RUN.toml (what was tested)."""

from __future__ import annotations

import json
from typing import Any

import numpy as np

FORMAT = "vtable-run/1"
SPECIMEN_KEYS = {"none": (), "rigid": ("weight_kip", "height_in"),
                 "sdof": ("weight_kip", "height_in", "frequency_hz", "damping"),
                 "shear_building": ("weights_kip", "heights_in", "frequencies_hz", "damping")}


def specimen_table(spec) -> dict[str, Any]:
    """A specimen's [specimen] table with exactly the run format's keys."""
    d = spec.to_dict()
    kind = d["kind"]
    out: dict[str, Any] = {"kind": kind}
    for k in SPECIMEN_KEYS[kind]:
        if k in d:
            out[k] = d[k]
    if kind == "shear_building" and "frequencies_hz" not in d:
        from vtable.analytic.structure import building_matrices, fixed_base_modes

        M, K, _ = building_matrices(spec)
        w, _ = fixed_base_modes(M, K)
        out["frequencies_hz"] = (w / (2 * np.pi)).tolist()
    return out


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string is a valid TOML basic string
    if isinstance(v, int | float | np.floating | np.integer):
        return repr(float(v)) if isinstance(v, float | np.floating) else str(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def dumps_toml(d: dict[str, Any]) -> str:
    """Minimal TOML writer for run metadata (top-level scalars, then tables)."""
    lines = [f"{k} = {_toml_value(v)}" for k, v in d.items() if not isinstance(v, dict)]
    for k, v in d.items():
        if isinstance(v, dict):
            lines.append(f"\n[{k}]")
            lines += [f"{kk} = {_toml_value(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"
