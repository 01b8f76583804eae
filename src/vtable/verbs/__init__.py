"""One library function per command-line verb: each takes plain arguments, does the work
and returns a typed result (`vtable.results`, `vtable.diagnose.result`) with `to_json()`,
`report()` and, where it draws a figure, `plot()`. The CLI (`vtable.cli`) only parses
arguments, calls one of these and formats the result; a script gets the same results by
calling them (``from vtable.verbs import modes`` or ``vtable.verbs.modes``).

The verbs live in one module per family, each importing what it needs at its top:
`analytic` (modes, margins, presets, a model's tf), `runs` (tf, a run's tf, identify),
`effects` (the user's effect files and names), `diagnosis` (compare, diagnose),
`simulation` (simulate, export_mjcf, demo), `studies` (assess, study) and `compensation` (drive).

This package imports none of them itself: `__getattr__` (PEP 562) imports a verb's module
the first time the verb is asked for. It is the one deliberately lazy import of the
package, because the families' dependencies take from a fraction of a second (the
analytical models: scipy.signal) to seconds (the diagnosis: numba kernels; the virtual
table: MuJoCo, Rerun; studies: Dask), and ``vtable --help`` or ``vtable presets`` must
not wait for the diagnosis and the virtual table to load.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # what `__getattr__` gives, for type checkers and editors
    from vtable.verbs.analytic import config_tf, margins, modes, presets
    from vtable.verbs.compensation import drive
    from vtable.verbs.diagnosis import DiagnosisInterrupted, compare, diagnose
    from vtable.verbs.effects import effect_names, load_controllers, load_effects
    from vtable.verbs.runs import identify, is_run, run_tf, tf
    from vtable.verbs.simulation import demo, export_mjcf, simulate, simulation_summary
    from vtable.verbs.studies import assess, study

#: public name -> the module of this package that defines it
VERBS: dict[str, str] = {
    "modes": "analytic", "margins": "analytic", "presets": "analytic", "config_tf": "analytic",
    "tf": "runs", "run_tf": "runs", "is_run": "runs", "identify": "runs",
    "load_effects": "effects", "effect_names": "effects", "load_controllers": "effects",
    "compare": "diagnosis", "diagnose": "diagnosis", "DiagnosisInterrupted": "diagnosis",
    "simulate": "simulation", "simulation_summary": "simulation", "export_mjcf": "simulation",
    "demo": "simulation",
    "assess": "studies", "study": "studies", "drive": "compensation",
}

__all__ = [  # = sorted(VERBS), spelled out for linters
    "DiagnosisInterrupted", "assess", "compare", "config_tf", "demo", "diagnose", "drive",
    "effect_names", "export_mjcf", "identify", "is_run", "load_controllers", "load_effects",
    "margins", "modes", "presets", "run_tf", "simulate", "simulation_summary", "study", "tf",
]


def __getattr__(name: str) -> Any:
    """`vtable.verbs.NAME`: the verb from its family's module, imported on first use."""
    if name not in VERBS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{VERBS[name]}"), name)
    globals()[name] = value  # found directly from now on
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(VERBS))
