"""Typed parameter objects that read and write TOML in the report's units.

Every physical field is declared with `quantity(unit, key=...)`: the object stores SI,
the TOML key names the unit (``weight_kip``, ``area_in2``), and conversion happens only
in `from_dict` / `to_dict`. Unknown keys, missing keys and out-of-range values are
one-line `VtableError`s naming the key. Every number must be finite (TOML allows nan and
inf) and below the plausible magnitude of its dimension (`vtable.units.PLAUSIBLE_MAX`:
10 kHz, 1e9 kg, ...), so an absurd value (1e300) is refused before a model uses it.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import tomllib
from pathlib import Path
from typing import Any, Self

from vtable import units
from vtable.errors import VtableError, did_you_mean

_MISSING = dataclasses.MISSING


def quantity(unit: str, key: str, *, default: Any = _MISSING, minimum: float | None = None,
             exclusive: bool = True, maximum: float | None = None, fraction: bool = False,
             source: str = "", doc: str = "", vector: bool = False) -> Any:
    """Declare a physical field stored in SI and written in TOML as `key` in `unit`.

    `minimum` bounds the SI value (strictly when `exclusive`), `maximum` bounds it from
    above (inclusive); `fraction` marks a damping ratio (a fraction of critical, so the
    error says "2 means 200 %"); `source` names the report table or equation the default
    comes from; `vector` fields take a list of numbers.
    """
    meta = {"unit": unit, "key": key, "minimum": minimum, "exclusive": exclusive,
            "maximum": maximum, "fraction": fraction,
            "source": source, "doc": doc, "vector": vector}
    if default is _MISSING:
        return dataclasses.field(metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def plain(key: str | None = None, *, default: Any = _MISSING, doc: str = "",
          toml: bool = True) -> Any:
    """A non-physical field (names, knob settings, nested parameter objects); `toml`
    False: not a key of the TOML table (held by the object, read and written by its own
    `from_dict`/`to_dict`)."""
    meta = {"key": key, "doc": doc, "toml": toml}
    if default is _MISSING:
        return dataclasses.field(metadata=meta)
    if isinstance(default, list | dict | set):
        raise TypeError("use an immutable default")
    return dataclasses.field(default=default, metadata=meta)


def _key(f: dataclasses.Field) -> str:
    return f.metadata.get("key") or f.name


class Params:
    """Mixin for frozen dataclasses declared with `quantity` and `plain` fields."""

    def __post_init__(self) -> None:
        for f, lo, hi, exclusive in _bounded(type(self)):
            v = getattr(self, f.name)
            if v is None:
                continue
            for x in (v if isinstance(v, tuple) else (v,)):
                if (lo is not None and not (math.isfinite(x)
                                            and (x > lo if exclusive else x >= lo))) or \
                        (hi is not None and not x <= hi):
                    _check_bounds(x, lo, exclusive, hi, f.metadata["unit"],
                                  f"{type(self).__name__}.{_key(f)}",
                                  f.metadata.get("fraction"))

    # -- TOML edge -------------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str = "") -> Self:
        """Build from a TOML table in the report's units; `where` prefixes error messages."""
        where = where or cls.__name__
        if not isinstance(d, dict):
            raise VtableError(f"{where}: expected a table, got {type(d).__name__}")
        fields = {_key(f): f for f in dataclasses.fields(cls)  # type: ignore[arg-type]
                  if f.metadata.get("toml", True)}
        unknown = sorted(set(d) - set(fields))
        if unknown:
            raise VtableError(f"{where}: unknown key {unknown[0]!r}"
                              f"{did_you_mean(unknown[0], fields)}; "
                              f"expected {', '.join(fields)}")
        kwargs = {}
        for key, f in fields.items():
            if key not in d:
                if f.default is _MISSING and f.default_factory is _MISSING:
                    raise VtableError(f"{where}: missing key {key!r}")
                continue
            kwargs[f.name] = _convert_in(d[key], f, f"{where}.{key}")
        try:
            return cls(**kwargs)
        except VtableError as e:
            raise VtableError(f"{where}: {e}") from None

    def to_dict(self) -> dict[str, Any]:
        """The TOML table in the report's units (round-trips through `from_dict`)."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            if v is None or not f.metadata.get("toml", True):
                continue
            if "unit" in f.metadata:
                v = _to_plain(units.from_si(v, f.metadata["unit"]))
            elif isinstance(v, Params):
                v = v.to_dict()
            elif isinstance(v, tuple):
                v = [x.to_dict() if isinstance(x, Params) else _to_plain(x) for x in v]
            out[_key(f)] = v
        return out

    @classmethod
    def from_toml(cls, path: str | Path, section: str | None = None) -> Self:
        """Read `path` (optionally one of its tables)."""
        d = read_toml(path)
        where = str(path)
        if section is not None:
            if section not in d:
                raise VtableError(f"{path}: missing table [{section}]")
            d, where = d[section], f"{path} [{section}]"
        return cls.from_dict(d, where)

    def replace(self, **changes: Any) -> Self:
        """A copy with some fields changed (SI values)."""
        return dataclasses.replace(self, **changes)  # type: ignore[type-var]

    @classmethod
    def sources(cls) -> dict[str, str]:
        """Field name -> the report table/equation its preset value comes from."""
        return {f.name: f.metadata.get("source", "")
                for f in dataclasses.fields(cls) if "unit" in f.metadata}  # type: ignore[arg-type]


@functools.cache
def _bounded(cls: type) -> tuple[tuple[dataclasses.Field, float | None, float | None, bool],
                                 ...]:
    """The fields of a `Params` class that carry bounds: (field, minimum, maximum,
    exclusive), worked out once per class (every parameter object checks them)."""
    return tuple((f, f.metadata.get("minimum"), f.metadata.get("maximum"),
                  f.metadata.get("exclusive", True))
                 for f in dataclasses.fields(cls)
                 if f.metadata.get("minimum") is not None or f.metadata.get("maximum") is not None)


def _check_bounds(v: float, lo: float | None, exclusive: bool, hi: float | None, unit: str,
                  what: str, fraction: bool) -> None:
    shown = units.from_si(v, unit) if math.isfinite(v) else v
    if lo is not None and (not math.isfinite(v) or (v <= lo if exclusive else v < lo)):
        rel = ">" if exclusive else ">="
        raise VtableError(f"{what} must be {rel} {units.from_si(lo, unit):g}, got {shown:g}")
    if hi is not None and not v <= hi:
        if fraction:
            raise VtableError(f"{what} is a fraction of critical damping, at most "
                              f"{units.from_si(hi, unit):g}; got {shown:g} ({shown:g} means "
                              f"{100 * shown:g} %)")
        raise VtableError(f"{what} must be <= {units.from_si(hi, unit):g}, got {shown:g}")


def check_number(v: Any, where: str, unit: str = "1") -> float:
    """A TOML value that must be a finite number in `unit` (not a bool, a string or a
    list), of plausible magnitude for its dimension (`units.PLAUSIBLE_MAX`) -> SI.

    Raises
    ------
    VtableError
        One line naming `where` and what was expected.
    """
    in_unit = f" in {unit}" if unit != "1" else ""
    if not _is_number(v):
        raise VtableError(f"{where}: expected a number{in_unit}, got {_show(v)}")
    try:
        x = float(v)
    except OverflowError:  # a TOML integer beyond any float
        x = math.inf
    if not math.isfinite(x) and not isinstance(v, int):
        raise VtableError(f"{where}: expected a finite number{in_unit}, got {v!r}")
    si = units.to_si(x, unit)
    dim = units.dimension(unit)
    limit = units.PLAUSIBLE_MAX[dim]
    if not abs(si) <= limit:
        shown = f"{x:.6g}" if math.isfinite(x) else _show(v)
        raise VtableError(f"{where}: {shown} {unit} is not a plausible {units.noun(dim)} (the "
                          f"limit is {units.from_si(limit, unit):g} {unit})")
    low = units.PLAUSIBLE_MIN.get(dim, 0.0)
    if 0 < abs(si) < low:
        raise VtableError(f"{where}: {x:.6g} {unit} is not a plausible {units.noun(dim)} "
                          f"(non-zero values start at {units.from_si(low, unit):g} {unit}; "
                          "write 0 if none is meant)")
    return si


def respelled(d: dict[str, Any], spellings: dict[str, tuple[str, dict[str, str], bool | None]],
              where: str) -> dict[str, Any]:
    """`d` with each quantity given by another unit's key turned into the format's key:
    `spellings` maps the format's key to (its unit, {other key: its unit}, whether it takes
    a list: True, a number: False, either: None) —
    ``"weight_kip": ("kip", {"mass_kg": "kg", ...}, False)``. The value is checked under
    the key given (`check_number`: a number, or a list of them; each ≥ 0, as every quantity
    spelled so is a magnitude) and converted; a mass given for a weight is its weight under
    standard gravity. Two keys of one quantity are an error."""
    out = dict(d)
    for key, (unit, others, lists) in spellings.items():
        given = [k for k in (key, *others) if k in d]
        if len(given) > 1:
            raise VtableError(f"{where}: {given[0]!r} and {given[1]!r} give the same "
                              "quantity; give one")
        if not given or given[0] == key:
            continue
        k = given[0]
        v = out.pop(k)
        if lists is not None and isinstance(v, list) != lists:
            raise VtableError(f"{where}.{k}: expected "
                              + (f"a list of numbers in {others[k]}" if lists else
                                 f"a number in {others[k]}") + f", got {_show(v)}")
        out[key] = [_respelled(x, f"{where}.{k}[{i}]", others[k], unit)
                    for i, x in enumerate(v)] if isinstance(v, list) else \
            _respelled(v, f"{where}.{k}", others[k], unit)
    return out


def _respelled(x: Any, where: str, given: str, unit: str) -> float:
    """A value `x` given in unit `given` (checked as `where`) in `unit` (a mass given for a
    weight: its weight under standard gravity)."""
    si = check_number(x, where, given)
    if si < 0:
        raise VtableError(f"{where}: expected a number >= 0 in {given}, got {x!r}")
    if units.dimension(given) == "mass" and units.dimension(unit) == "force":
        si *= units.G
    return units.from_si(si, unit)


def _show(v: Any) -> str:
    s = repr(v)
    return s if len(s) <= 40 else s[:37] + "..."


def _check_plain(v: Any, f: dataclasses.Field, where: str) -> Any:
    """Plain fields declared `str`, `int` or `float` take only that kind of TOML value."""
    t = str(f.type).replace(" ", "")
    if t in ("str", "str|None") and not isinstance(v, str):
        raise VtableError(f"{where}: expected a string, got {_show(v)}")
    if t == "int" and (not isinstance(v, int) or isinstance(v, bool)):
        raise VtableError(f"{where}: expected a whole number, got {_show(v)}")
    if t == "float":
        return check_number(v, where)
    return v


def _to_plain(v: Any) -> Any:
    if hasattr(v, "tolist"):
        return v.tolist()
    return v


def _convert_in(v: Any, f: dataclasses.Field, where: str) -> Any:
    unit = f.metadata.get("unit")
    if unit is None:
        return _check_plain(v, f, where)
    if f.metadata.get("vector"):
        if not isinstance(v, list) or not v:
            raise VtableError(f"{where}: expected a non-empty list of numbers in {unit}, got "
                              f"{_show(v)}")
        return tuple(check_number(x, f"{where}[{i}]", unit) for i, x in enumerate(v))
    return check_number(v, where, unit)


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def read_toml(path: str | Path) -> dict[str, Any]:
    """Parse a TOML file (a UTF-8 byte-order mark, as some editors write, is allowed); a
    missing or malformed file is a one-line error naming it."""
    p = Path(path)
    try:
        text = p.read_bytes().decode("utf-8").removeprefix("\ufeff")
        return tomllib.loads(text)
    except FileNotFoundError:
        raise VtableError(f"{p}: no such file") from None
    except tomllib.TOMLDecodeError as e:
        raise VtableError(f"{p}: malformed TOML: {e}") from None
    except UnicodeDecodeError:
        raise VtableError(f"{p}: not UTF-8 text (a TOML file is expected)") from None
    except OSError as e:
        raise VtableError(f"{p}: cannot read: {e.strerror or type(e).__name__}") from None
