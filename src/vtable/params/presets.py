"""Named presets from the report, read from the TOML files in ``data/``.

Names are ``family`` or ``family:row`` with the report's table number, e.g.
``table6.1:standard``, ``table7.2:k_o=25``, ``table9.1``, ``table5.1``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

from vtable import units
from vtable.errors import VtableError, did_you_mean
from vtable.params.base import read_toml
from vtable.params.loops import (
    HorizontalSpring,
    HybridParams,
    MechanicalParams,
    OpenLoop,
    RockingSpring,
    TableSDOFParams,
)
from vtable.params.specimen import SDOFSpecimen, Specimen, specimen_from_dict
from vtable.params.table import TableHardware


@cache
def data(name: str) -> dict[str, Any]:
    """The sections of data/NAME.toml as read (report units, read once): eerc, models,
    specimens, uniaxial_multibody, lnec_st1d. Callers must not modify the result."""
    path = resources.files("vtable.params.data") / f"{name}.toml"
    with resources.as_file(path) as p:
        return read_toml(p)


@cache
def eerc_table() -> TableHardware:
    """The EERC table (data/eerc.toml)."""
    return TableHardware.from_dict(data("eerc"), "eerc.toml")


def anti_alias_hz() -> float:
    """The measurement chain's anti-aliasing cut-off (Hz), §2.3 (data/eerc.toml)."""
    return float(data("eerc")["acquisition"]["anti_alias_hz"])


@dataclass(frozen=True)
class PitchSprings:
    """§8.6.2: the vertical actuators' pitch loop as a spring k_v (N m/rad) and dashpot
    c_v (N m s/rad) at the §8.6.3 coupled table-structure frequency f_coupled (Hz)."""

    k_v: float
    c_v: float
    f_coupled: float


def pitch_springs() -> PitchSprings:
    """The §8.6.2 springs of the pitch loop, in SI (models.toml [section8_6_2])."""
    d = data("models")["section8_6_2"]
    return PitchSprings(units.to_si(d["k_v_lb_in_per_rad"], "lb-in/rad"),
                        units.to_si(d["c_v_lb_in_s_per_rad"], "lb-in-s/rad"),
                        float(d["f_coupled_hz"]))


def specimen(name: str) -> Specimen:
    """A specimen from data/specimens.toml: none, concrete_blocks, sdof_frame, ..."""
    d = data("specimens")
    if name not in d:
        raise VtableError(f"unknown specimen preset {name!r}{did_you_mean(name, d)}; "
                          f"expected one of {', '.join(d)}")
    return specimen_from_dict(d[name], f"specimens.toml [{name}]")


def _row(family: str, name: str) -> dict[str, Any]:
    key = family.replace(".", "_")
    rows = data("models").get(key)
    if rows is None:
        raise VtableError(f"unknown preset family {family!r}")
    if name not in rows:
        raise VtableError(f"unknown row {name!r} of {family}; expected one of "
                          f"{', '.join(rows)}")
    return rows[name]


def rows(family: str) -> list[str]:
    """Row names of a tabulated family (table6.1, table7.1, table7.2)."""
    return list(data("models")[family.replace(".", "_")])


def _split(name: str, family: str) -> str:
    fam, _, row = name.partition(":")
    if fam != family or not row:
        raise VtableError(f"expected a preset name like {family}:ROW, got {name!r}")
    return row


def open_loop(name: str) -> OpenLoop:
    """A Table 6.1 row, e.g. ``table6.1:standard``."""
    row = _split(name, "table6.1")
    return OpenLoop.from_dict(_row("table6.1", row), f"models.toml [table6_1.{row}]")


def table_sdof(name: str) -> TableSDOFParams:
    """A Table 7.1 or 7.2 row, e.g. ``table7.2:k_o=25``."""
    fam, _, row = name.partition(":")
    if fam not in ("table7.1", "table7.2") or not row:
        raise VtableError(f"expected table7.1:ROW or table7.2:ROW, got {name!r}")
    d = dict(_row(fam, row))
    return TableSDOFParams.from_dict(d, f"models.toml [{fam}.{row}]")


def model_part(key: str, name: str, cls: type) -> Any:
    """One part of a physical parameter set, e.g. ``model_part("table8_1", "rocking",
    RockingSpring)`` reads models.toml [table8_1.rocking]."""
    return cls.from_dict(data("models")[key][name], f"models.toml [{key}.{name}]")


def physical(key: str) -> tuple[SDOFSpecimen, float, float, Callable[[str, type], Any]]:
    """For the physical sets (Tables 8.1, 5.1): the structure (specimens.toml [key]), the
    table mass and inertia (eerc.toml), and part(name, cls) reading models.toml [key.name]."""
    spec = specimen(key)
    assert isinstance(spec, SDOFSpecimen)
    t = eerc_table().geometry
    return spec, t.mass, t.pitch_inertia, lambda name, cls: model_part(key, name, cls)


def hybrid(name: str = "table9.1") -> HybridParams:
    """Table 9.1 (ratios as printed) or Table 8.1 (physical values, converted)."""
    if name == "table9.1":
        return HybridParams.from_dict(data("models")["table9_1"], "models.toml [table9_1]")
    if name == "table8.1":
        spec, m_t, inertia, part = physical("table8_1")
        return HybridParams.from_physical(spec, m_t, inertia, part("open_loop", OpenLoop),
                                          part("rocking", RockingSpring),
                                          title="hybrid model, Table 8.1", source="Table 8.1")
    raise VtableError(f"unknown hybrid preset {name!r}; expected table9.1 or table8.1")


def mechanical(name: str = "table9.3") -> MechanicalParams:
    """Table 9.3 (ratios as printed) or Table 5.1 (physical values, converted)."""
    if name == "table9.3":
        return MechanicalParams.from_dict(data("models")["table9_3"], "models.toml [table9_3]")
    if name == "table5.1":
        spec, m_t, inertia, part = physical("table5_1")
        return MechanicalParams.from_physical(spec, m_t, inertia,
                                              part("horizontal", HorizontalSpring),
                                              part("rocking", RockingSpring),
                                              title="mechanical model, Table 5.1",
                                              source="Table 5.1")
    raise VtableError(f"unknown mechanical preset {name!r}; expected table9.3 or table5.1")


def hybrid_rocking() -> RockingSpring:
    """Table 8.1's rocking spring and dashpot k_θ, c_θ."""
    return physical("table8_1")[3]("rocking", RockingSpring)
