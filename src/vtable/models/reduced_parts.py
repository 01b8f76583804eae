"""The parts of a reduced model that a fit builds again and again with the same values, kept
for the last few: a fit builds the model hundreds of times, and each of a Jacobian's
columns moves one parameter (a servo-loop, specimen, table or effect value), so most of
the parts are the same as last time.

- `mechanics_on`: the model's table (`Physics.on_table`), by table and calibrated table
  values, and its rigid-body matrices with the specimen (`linear_table.mechanics`), by
  that table and specimen;
- `base_servo`: one horizontal actuator's constants for the base loop
  (`Physics.base_hydraulics`), by that table and the open loop;
- `pitch_loop`: the vertical actuators' pitch loop of that table
  (`ServoLaw.dof_loop`, the pitch effect's `set_rocking`);
- `lumped_law`: the horizontal actuators lumped into one (`ServoLaw.lumped`), by that
  table, those constants and the stages with their values;
- `table_view`: what the effects read of that table (`effects.table.TableView`);
- `kept_histories`: a model's integrated histories on a command, by its dynamics: a model
  with output filters is stepped again with the same dynamics when a fit moves only the
  filters' parameters (a sensor filter's grid, its least-squares steps in its own
  parameters, their Jacobian's columns).

Every key holds the objects it names by identity (kept with the result, so that an id
stays theirs) and the values by value; nothing kept is changed in place: frozen
dataclasses, the mechanics' matrices read-only, and the laws' arrays only read (they stay
writeable: the compiled integrators take them as they take any model's).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from vtable.effects.table import TableView
from vtable.hydraulics import group_law
from vtable.models import physics as phys
from vtable.models.linear_table import mechanics

#: entries kept by each cache
KEPT = 16
#: the integrated histories kept at most (bytes: `kept_histories`)
HISTORIES_MAX = 64 << 20

_TABLES: dict = {}
_MECHANICS: dict = {}
_SERVOS: dict = {}
_PITCH: dict = {}
_LAWS: dict = {}
_VIEWS: dict = {}
_HISTORIES: dict = {}


def _hit(cache: dict, key: tuple, held: tuple) -> Any:
    """`cache`'s value for `key` whose held objects are `held` (by identity), or None."""
    hit = cache.get(key)
    if hit is not None and len(hit[0]) == len(held) and \
            all(a is b for a, b in zip(hit[0], held, strict=True)):
        return hit[1]
    return None


def _kept(cache: dict, key: tuple, held: tuple, make: Callable[[], Any]) -> Any:
    """`cache`'s value for `key` whose held objects are `held` (`_hit`), else `make()`
    kept there (the oldest entry dropped beyond `KEPT`)."""
    value = _hit(cache, key, held)
    if value is None:
        value = make()
        _keep(cache, key, (held, value))
    return value


def _keep(cache: dict, key: tuple, entry: tuple) -> None:
    """`cache[key] = entry`, the oldest entry dropped beyond `KEPT` (fits in threads share
    the caches: one dropped by another thread meanwhile is left to it)."""
    if len(cache) >= KEPT:
        with contextlib.suppress(RuntimeError, KeyError, StopIteration):
            cache.pop(next(iter(cache)))
    cache[key] = entry


def mechanics_on(ph: phys.Physics, vt) -> tuple:
    """(`ph.on_table(vt)`, its `mechanics` with `ph`'s specimen, no actuator Jacobian). The
    table is kept by its calibrated values, so that a specimen moved alone keeps its table
    (and every part kept by table); the specimen is a key by its value (each fitted point
    unpacks a new one), by its identity when it cannot be hashed. The matrices are
    read-only."""
    vt_on = _kept(_TABLES, (id(vt), tuple(sorted(ph.table.items())), ph.force_measured),
                  (vt,), lambda: ph.on_table(vt))
    spec = ph.specimen
    try:  # by value (the dict compares equal keys), else by identity, held
        key, held = (id(vt_on), hash(spec), spec), (vt_on,)
    except TypeError:
        key, held = (id(vt_on), id(spec)), (vt_on, spec)

    def make() -> tuple:
        mech = mechanics(vt_on, spec, jacobian=False)
        for a in mech[:3]:
            a.flags.writeable = False
        return mech

    return vt_on, _kept(_MECHANICS, key, held, make)


def base_servo(ph: phys.Physics, vt):
    """`Physics.base_hydraulics(ph, vt)`, kept by table and open loop."""
    return _kept(_SERVOS, (id(vt), ph.open_loop), (vt,), lambda: phys.base_hydraulics(ph, vt))


def pitch_loop(vt) -> tuple[float, float, float, float]:
    """(a, b_q, b_v, f) of the vertical actuators' pitch loop of `vt` (`ServoLaw.dof_loop`)."""
    return _kept(_PITCH, (id(vt),), (vt,), lambda: group_law(vt, "vertical").dof_loop("pitch"))


def lumped_law(vt, servo, stages: Sequence[tuple[Any, dict[str, float]]]):
    """The horizontal group's law of `vt` with the constants `servo` and `stages` (stage,
    its values), lumped into one actuator on x (`ServoLaw.lumped`)."""
    key = (id(vt), servo, tuple((id(s), tuple(sorted(p.items()))) for s, p in stages))
    return _kept(_LAWS, key, (vt, *(s for s, _ in stages)),
                 lambda: group_law(vt, "horizontal", servo, stages=stages).lumped("x"))


def table_view(vt, piston_area: float):
    """`TableView.of(vt, piston_area)`, kept by table and area."""
    return _kept(_VIEWS, (id(vt), piston_area), (vt,),
                 lambda: TableView.of(vt, piston_area=piston_area))


def kept_histories(model, t, x_c):
    """`model.histories(t, x_c)` (a `ReducedModel`'s), kept by what the integration reads:
    its arrays (`ReducedModel.integrated`), its force elements' values `pe`, its step, its
    compiled element, and the command arrays themselves (held: a fit drives every point by
    the same arrays). At most `KEPT` of them and `HISTORIES_MAX` bytes; those kept are
    read-only (`modal.filtered` hands a filter a copy of any it would read)."""
    parts = (*model.integrated, model.pe, getattr(model, "ia", ()), getattr(model, "ib", ()))
    arrays = [np.asarray(a) for a in parts]
    key = (id(t), id(x_c), id(model.element.module), id(model.elem), model.python,
           model.linear, model.ne, model.max_step, tuple(a.shape for a in arrays),
           b"".join(a.tobytes() for a in arrays))
    held = (t, x_c, model.element.module, model.elem)
    h = _hit(_HISTORIES, key, held)
    if h is not None:
        return h
    h = model.histories(t, x_c)
    kept = h[3:]  # (not the command: with no upsampling it is the caller's)
    if sum(a.nbytes for a in kept) <= HISTORIES_MAX // 4:
        for a in kept:
            a.flags.writeable = False
        _keep(_HISTORIES, key, (held, h))
        while sum(a.nbytes for _, e in _HISTORIES.values() for a in e[3:]) > HISTORIES_MAX:
            with contextlib.suppress(RuntimeError, KeyError, StopIteration):
                _HISTORIES.pop(next(iter(_HISTORIES)))
    return h
