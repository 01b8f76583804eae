"""Named configurations and TOML model files -> analytical models (used by the CLI).

A model file::

    model = "hybrid"            # servo | table_sdof | hybrid | mechanical | rc_filter
                                # | two_directional | mdof_hybrid
    preset = "table9.1"         # optional starting point; [parameters] overrides it
    height_in = 219.0           # optional, gives θ outputs for hybrid/mechanical
    [parameters]                # the model's parameter table, report units
    open_loop = { f_o_hz = 9.6, xi_o = 0.606, k_o_per_s = 29.5 }

or, for `hybrid`, physical values on the EERC table: ``[specimen]`` (run-format keys),
``[open_loop]`` and ``[rocking]`` (k_theta_lb_in_per_rad, c_theta_lb_in_s_per_rad).

What a model file may say is bounded to what is physical, so that a typo is one line and
never an overflow or a hang: every number finite and of plausible magnitude
(`vtable.units.PLAUSIBLE_MAX`: frequencies and gains below 10 kHz or 1e4 1/s, masses
below 1e9 kg, ...), structural damping ratios (ξ_s, a specimen's damping) at most 1,
the damping ratios of servo loops and equivalent springs (ξ_o, ξ_θ, ξ_h, ξ_p) at most
`XI_LOOP_MAX` = 3 (Table 9.1's ξ_θ is 1.115), mass ratios u at most `MAX_MASS_RATIO`,
inertia ratios v at most `MAX_INERTIA_RATIO`, shear buildings at most 50 storeys.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from vtable.analytic.base import LinearModel
from vtable.analytic.mdof import MDOFHybrid
from vtable.analytic.mechanical import MechanicalModel
from vtable.analytic.pitch import HybridModel, TwoDirectionalTable, two_directional
from vtable.analytic.rcfilter import RCFilterServo
from vtable.analytic.sdof import TableSDOF
from vtable.analytic.servo import ServoLoop
from vtable.errors import UnstableError, VtableError, did_you_mean
from vtable.params import presets
from vtable.params.base import Params, check_number, read_toml
from vtable.params.loops import (
    HybridParams,
    MechanicalParams,
    OpenLoop,
    RockingSpring,
    TableSDOFParams,
    TwoDirectionalParams,
)
from vtable.params.specimen import SDOFSpecimen, specimen_from_dict
from vtable.params.table import ServoConstants

#: the built-in EERC configuration: the SDOF frame on the table, hybrid model (Table 9.1)
DEFAULT = "eerc-sdof"
#: the report's coupled modes of that configuration, (f Hz, damping ratio) per mode: Table 9.2
DEFAULT_REFERENCE = ("Table 9.2", ((2.5391, 0.0401), (8.1906, 0.2590)))
SDOF_HEIGHT = presets.specimen("table8_1").height  # Table 8.1 structural height


def _named() -> dict[str, Callable[[], LinearModel]]:
    named: dict[str, Callable[[], LinearModel]] = {
        "eerc-sdof": lambda: HybridModel(presets.hybrid("table9.1"), height=SDOF_HEIGHT,
                                         title="EERC table + SDOF frame (hybrid, Table 9.1)"),
        "table9.1": lambda: HybridModel(presets.hybrid("table9.1"), height=SDOF_HEIGHT),
        "table8.1": lambda: HybridModel(presets.hybrid("table8.1"),
                                        height=presets.specimen("table8_1").height),
        "table9.3": lambda: MechanicalModel(presets.mechanical("table9.3"), height=SDOF_HEIGHT),
        "table5.1": lambda: MechanicalModel(presets.mechanical("table5.1"),
                                            height=presets.specimen("table5_1").height),
        "two-directional": lambda: TwoDirectionalTable(two_directional(21.0)),
        "two-directional-13hz": lambda: TwoDirectionalTable(two_directional(13.0)),
        "table-b.5": lambda: RCFilterServo(presets.eerc_table().servo,
                                           title="bare table with RC filter (Table B.5)"),
        "bare-physical": lambda: ServoLoop.from_servo(presets.eerc_table().servo),
    }
    for row in presets.rows("table6.1"):
        named[f"table6.1:{row}"] = (lambda r=row: ServoLoop(
            presets.open_loop(f"table6.1:{r}"), title=f"bare table, Table 6.1 {r}"))
    for fam in ("table7.1", "table7.2"):
        for row in presets.rows(fam):
            named[f"{fam}:{row}"] = (lambda f=fam, r=row: TableSDOF(
                presets.table_sdof(f"{f}:{r}"), title=f"table + SDOF, {f.title()} {r}"))
    return named


def names() -> list[str]:
    """Every named configuration."""
    return list(_named())


def load(name_or_path: str) -> LinearModel:
    """A named configuration, or a model TOML file (a path ending in .toml)."""
    if name_or_path.endswith(".toml") or Path(name_or_path).is_file():
        return from_file(name_or_path)
    named = _named()
    if name_or_path not in named:
        raise VtableError(f"unknown configuration {name_or_path!r}"
                          f"{did_you_mean(name_or_path, named)}; expected a .toml file or "
                          f"one of: {', '.join(named)}")
    return named[name_or_path]()


_KINDS: dict[str, tuple[type, Callable[[Any, float | None], LinearModel]]] = {
    "servo": (OpenLoop, lambda p, h: ServoLoop(p)),
    "table_sdof": (TableSDOFParams, lambda p, h: TableSDOF(p)),
    "hybrid": (HybridParams, lambda p, h: HybridModel(p, height=h)),
    "mechanical": (MechanicalParams, lambda p, h: MechanicalModel(p, height=h)),
    "rc_filter": (ServoConstants, lambda p, h: RCFilterServo(p)),
    "two_directional": (TwoDirectionalParams, lambda p, h: TwoDirectionalTable(p)),
}
_PRESET_PARAMS: dict[str, Callable[[str], Any]] = {
    "servo": presets.open_loop, "table_sdof": presets.table_sdof,
    "hybrid": presets.hybrid, "mechanical": presets.mechanical,
    "rc_filter": lambda name: presets.eerc_table().servo if name == "table-b.5" else
    (_ for _ in ()).throw(VtableError(f"unknown rc_filter preset {name!r}; expected table-b.5")),
}
#: the largest damping ratio of a servo loop or an equivalent spring (fraction of critical)
XI_LOOP_MAX = 3.0
#: the largest specimen-to-table mass ratio u = m_s/m_t (Table 7.2 goes to 2)
MAX_MASS_RATIO = 100.0
#: the largest inertia ratio v = m_s h²/I (Table 9.1: 6.8)
MAX_INERTIA_RATIO = 1e4
_RATIO_MAX = {"mass_ratio": MAX_MASS_RATIO, "inertia_ratio": MAX_INERTIA_RATIO}
_TOP = {"model", "preset", "title", "height_in", "parameters", "specimen", "open_loop",
        "rocking", "building"}


def from_file(path: str | Path) -> LinearModel:
    """Build the model a TOML model file describes (see the module docstring)."""
    d = read_toml(path)
    where = str(path)
    if isinstance(d.get("format"), str) and d["format"].startswith("vtable-run/"):
        raise VtableError(f"{where}: a run file ({d['format']}), not a model configuration "
                          "(a preset, `vtable presets`, or a model .toml: "
                          "docs/how-to/command-line.md); what a run holds: vtable tf RUN.toml "
                          "(its x_t/x_c), vtable identify RUN.toml (its loop, margin and "
                          "specimen)")
    unknown = sorted(set(d) - _TOP, key=str)
    if unknown:
        raise VtableError(f"{where}: unknown key {unknown[0]!r}"
                          f"{did_you_mean(unknown[0], _TOP)}; "
                          f"expected {', '.join(sorted(_TOP))}")
    kind = d.get("model")
    kinds = [*_KINDS, "mdof_hybrid"]
    if kind not in kinds:
        raise VtableError(f"{where}: model must be one of {', '.join(kinds)}, got {kind!r}")
    height = d.get("height_in")
    if height is not None:
        height = check_number(height, f"{where}: height_in", "in")
        if not height > 0:
            raise VtableError(f"{where}: height_in must be a positive number")
    title = d.get("title", "")
    if not isinstance(title, str):
        raise VtableError(f"{where}: title must be a string, got {title!r:.40}")
    for k in ("parameters", "specimen", "open_loop", "rocking", "building"):
        if k in d and not isinstance(d[k], dict):
            raise VtableError(f"{where}: [{k}] must be a table, got {type(d[k]).__name__}")
    if kind == "mdof_hybrid":
        # the eq 4.5 inverse problem tries stiffnesses whose modes may be complex; it
        # checks its result and says so, so numpy's warnings would only add noise
        with np.errstate(invalid="ignore"):
            try:
                model = _mdof_from(d, where)
            except UnstableError:
                raise
            except VtableError as e:
                raise VtableError(str(e) if str(e).startswith(where) else f"{where}: {e}") \
                    from None
    elif kind == "hybrid" and "parameters" not in d and "preset" not in d:
        model = _hybrid_physical(d, where)
    else:
        cls, make = _KINDS[kind]
        base: dict[str, Any] = {}
        if "preset" in d:
            if kind not in _PRESET_PARAMS:
                raise VtableError(f"{where}: model {kind!r} has no presets")
            if not isinstance(d["preset"], str):
                raise VtableError(f"{where}: preset must be a string, got {d['preset']!r:.40}")
            base = _PRESET_PARAMS[kind](d["preset"]).to_dict()
        params = cls.from_dict(_merge(base, d.get("parameters", {}), where),
                               f"{where} [parameters]")
        check_physical(params, f"{where} [parameters]")
        model = make(params, height)
    if title:
        model.title = title
    model.check_stable()
    return model


def check_physical(p: Params, where: str) -> None:
    """Bounds the parameter classes leave open: damping ratios (structural ξ_s <= 1, loop
    and equivalent-spring ξ <= `XI_LOOP_MAX`) and the mass and inertia ratios."""
    for f in dataclasses.fields(p):  # type: ignore[arg-type]
        v = getattr(p, f.name)
        key = f.metadata.get("key") or f.name
        if isinstance(v, Params):
            check_physical(v, f"{where}.{key}")
        elif isinstance(v, float) and f.metadata.get("unit") == "1":
            if key.startswith("xi"):
                hi = 1.0 if key == "xi_s" else XI_LOOP_MAX
                if v > hi:
                    kind = "structural" if key == "xi_s" else "loop"
                    raise VtableError(f"{where}.{key}: a {kind} damping ratio is a fraction of "
                                      f"critical, at most {hi:g}; got {v:g} ({v:g} means "
                                      f"{100 * v:g} %)")
            elif key in _RATIO_MAX and v > _RATIO_MAX[key]:
                raise VtableError(f"{where}.{key}: {v:g} is not a plausible ratio (at most "
                                  f"{_RATIO_MAX[key]:g})")


def _merge(base: dict[str, Any], over: Any, where: str) -> dict[str, Any]:
    if not isinstance(over, dict):
        raise VtableError(f"{where} [parameters]: expected a table")
    out = dict(base)
    for k, v in over.items():
        out[k] = _merge(out[k], v, where) if isinstance(v, dict) and isinstance(
            out.get(k), dict) else v
    return out


def _hybrid_physical(d: dict[str, Any], where: str) -> HybridModel:
    for k in ("specimen", "open_loop", "rocking"):
        if k not in d:
            raise VtableError(f"{where}: a physical hybrid model needs [{k}]")
    spec = specimen_from_dict(d["specimen"], f"{where} [specimen]")
    if not isinstance(spec, SDOFSpecimen):
        raise VtableError(f"{where} [specimen]: the hybrid model carries a sdof specimen; "
                          "use model = \"mdof_hybrid\" for a shear building")
    geo = presets.eerc_table().geometry
    ol = OpenLoop.from_dict(d["open_loop"], f"{where} [open_loop]")
    check_physical(ol, f"{where} [open_loop]")
    p = HybridParams.from_physical(spec, geo.mass, geo.pitch_inertia, ol,
                                   RockingSpring.from_dict(d["rocking"], f"{where} [rocking]"),
                                   title=spec.title + _initial_stiffness(spec))
    check_physical(p, f"{where} (derived from [specimen], [open_loop], [rocking])")
    return HybridModel(p, height=spec.height)


def _mdof_from(d: dict[str, Any], where: str) -> MDOFHybrid:
    for k in ("building", "open_loop", "rocking"):
        if k not in d:
            raise VtableError(f"{where}: model mdof_hybrid needs [{k}]")
    b = dict(d["building"])
    b.setdefault("kind", "shear_building")
    if b["kind"] != "shear_building":
        raise VtableError(f"{where} [building].kind: expected \"shear_building\", got "
                          f"{b['kind']!r:.40}")
    building = specimen_from_dict(b, f"{where} [building]")
    geo = presets.eerc_table().geometry
    ol = OpenLoop.from_dict(d["open_loop"], f"{where} [open_loop]")
    check_physical(ol, f"{where} [open_loop]")
    return MDOFHybrid(ol, geo.mass, geo.pitch_inertia,
                      RockingSpring.from_dict(d["rocking"], f"{where} [rocking]"), building,
                      title=(f"{building.n}-storey building on the hybrid table"
                             + _initial_stiffness(building)))


def _initial_stiffness(spec) -> str:
    """What a linear model's title says of a specimen that declares yielding storeys."""
    if getattr(spec, "hysteresis", None) is None:
        return ""
    return (" (its yielding storeys at their initial stiffness: this analytical model is "
            "linear)")
