"""The registry of effects: the catalog's (one module each, names from
docs/effects.md) and the ones users register from their own files."""

from __future__ import annotations

import functools
from pathlib import Path

from vtable.effects.base import Effect
from vtable.effects.verbs import check_verbs
from vtable.errors import VtableError, did_you_mean
from vtable.hydraulics.stage import Stage
from vtable.userfile import Registry

#: the catalog, in the spec's order (modules of vtable.effects)
BUILT_IN = ("pitch_flexibility", "force_feedback_filter", "valve_flow_nonlinearity",
            "actuator_friction", "flow_saturation", "valve_dynamics", "oil_column_air",
            "amplitude_dependent_damping", "foundation_compliance", "sensor_filter",
            "platen_resonator", "storey_yield", "sensor_mount", "specimen_degradation",
            "sensor_offset")

#: what the standard virtual table has beyond the chapter-7 base: its pitch system (Table
#: 8.1) and the RC filter on the horizontal ΔP feedback (Table B.5), at their defaults
STANDARD = ("pitch_flexibility", "force_feedback_filter")
#: the standard table's RC filter among them (`simulate --no-rc-filter` leaves it out)
STANDARD_RC_FILTER = STANDARD[1]


def _check(e: Effect, where: str) -> None:
    if not isinstance(e, Effect):
        raise VtableError(f"{where}: register() takes an Effect instance, got "
                          f"{type(e).__name__}")
    if not isinstance(e.name, str) or not e.name.isidentifier():
        raise VtableError(f"{where}: effect name {e.name!r} must be an identifier")
    for k in ("physics", "section", "signature"):
        if not isinstance(getattr(e, k), str) or not getattr(e, k).strip():
            raise VtableError(f"{where}: effect {e.name!r} needs a `{k}` text")
    if not isinstance(e.params, tuple | list):
        raise VtableError(f"{where}: effect {e.name!r}: params must be a tuple of Param")
    seen = set()
    for q in e.params:
        if q.name in seen:
            raise VtableError(f"{where}: effect {e.name!r} declares parameter {q.name!r} twice")
        seen.add(q.name)
        q.check_declaration(f"{where}: effect {e.name!r}")
    if type(e).apply is Effect.apply and (type(e).reduced is Effect.reduced
                                           or type(e).virtual is Effect.virtual):
        raise VtableError(f"{where}: effect {e.name!r} defines neither apply(m, p) nor both "
                          "reduced(m, p) and virtual(v, p)")


EFFECTS: Registry[Effect] = Registry(
    BUILT_IN, "vtable.effects.{}", "EFFECT", prefix="vtable_user_effects_",
    flag="--effects-from", check=_check,
    unknown=lambda name, known: (f"unknown effect {name!r}{did_you_mean(name, known)}; the "
                                 f"registry has {', '.join(known)}"))


@functools.cache
def stock_stages() -> tuple[Stage, ...]:
    """The hydraulic stages the catalog's effects may add (`Effect.stages`), in the
    catalog's order: the reduced model's nonlinear element carries them all behind flags
    (`vtable.hydraulics.compose`), so every set of them shares one compiled integrator."""
    return tuple(dict.fromkeys(s for name in BUILT_IN for s in get(name).stages))


def register(effect: Effect) -> Effect:
    """Add a user's effect to the registry (ranked with the catalog's, named in the JSON,
    the report and the recording). A name the catalog has is refused, and so is a verb
    one model cannot realise (`verbs.check_verbs`); registering the same user effect
    again replaces it."""
    where = EFFECTS.loading_file or getattr(effect, "__module__", "") or "register()"
    if getattr(effect, "name", None) in BUILT_IN:
        raise VtableError(f"{where}: effect name {effect.name!r} clashes with a built-in "
                          "effect; choose another name")
    _check(effect, where)
    check_verbs(effect, where)
    return EFFECTS.add(effect.name, effect, where)


def get(name: str) -> Effect:
    return EFFECTS.get(name)


def names() -> list[str]:
    """Every registered effect: the catalog's, then users'."""
    return EFFECTS.names()


def default_candidates() -> list[str]:
    """The effects `diagnose` tries when not told which: every registered one."""
    return names()


def parse_spec(text: str, where: str = "--effect") -> tuple[str, dict[str, float]]:
    """'name' or 'name:param=value,param=value' (values in the effect's units)."""
    name, _, rest = text.partition(":")
    e = get(name.strip())
    values: dict[str, float] = {}
    for item in filter(None, (x.strip() for x in rest.split(","))):
        k, eq, v = item.partition("=")
        if not eq:
            raise VtableError(f"{where} {text!r}: expected PARAM=VALUE, got {item!r}")
        try:
            values[k.strip()] = float(v)
        except ValueError:
            raise VtableError(f"{where} {text!r}: {v.strip()!r} is not a number") from None
    e.check(values, f"{where} {e.name}")
    return e.name, values


def is_user(name: str) -> bool:
    return EFFECTS.is_user(name)


def load_file(path: str | Path) -> list[str]:
    """Run a user's effects file (plain Python that calls `register`); returns the names it
    registered. Any problem — a missing file, a syntax error, an exception while it runs,
    a bad declaration, a name clash, registering nothing — is one line naming the file
    (`vtable.userfile.run_user_file`)."""
    return EFFECTS.load_file(path, "registers no effect (call vtable.effects.register(...))")


def loaded(path: str | Path) -> bool:
    """Whether this process has loaded the file at `path` (`load_file`)."""
    return EFFECTS.loaded(path)


def source_file(name: str) -> str | None:
    """The file a user's effect was loaded from (`load_file`); None for the catalog's and
    for one registered from code (another process cannot load it again)."""
    return EFFECTS.source_file(name)
