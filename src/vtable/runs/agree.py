"""Whether two runs declare the same thing: their parsed declarations (`Run.declared`,
every quantity in one unit) compared value by value, so that one specimen written in kip
and inches in one run and in kilograms and metres in another is one specimen.

Numbers agree within `RTOL` (relative): a value converted from another unit and printed
to a few digits comes back a few parts in 10⁷ off, and a lab's declared values are
nominal to far more than 0.01 %; two states of one specimen differ by percents, which a
state is declared for (`[specimen] state`)."""

from __future__ import annotations

import dataclasses
import math
from numbers import Real
from typing import Any

import numpy as np

#: relative tolerance of two declared numbers that are one value
RTOL = 1e-4


def agree(a: Any, b: Any, rtol: float = RTOL) -> bool:
    """`a` and `b` (declarations: dataclasses, dicts, sequences, arrays, numbers,
    strings) equal, numbers within `rtol`; a dataclass's fields that take no part in its
    equality (`compare=False`: notes) are not compared."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and a.dtype.kind == b.dtype.kind and (
            bool(np.array_equal(a, b)) if a.dtype.kind not in "fc"
            else bool(np.allclose(a, b, rtol=rtol, atol=0.0, equal_nan=True)))
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return type(a) is type(b) and all(
            agree(getattr(a, f.name), getattr(b, f.name), rtol)
            for f in dataclasses.fields(a) if f.compare)
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and \
            all(agree(a[k], b[k], rtol) for k in a)
    if isinstance(a, list | tuple):
        return isinstance(b, list | tuple) and len(a) == len(b) and \
            all(agree(x, y, rtol) for x, y in zip(a, b, strict=True))
    if isinstance(a, bool) or isinstance(b, bool):
        return type(a) is type(b) and a == b
    if _number(a) and _number(b):
        return math.isclose(a, b, rel_tol=rtol, abs_tol=0.0) or (math.isnan(a) and math.isnan(b))
    return bool(a == b)


def _number(x: Any) -> bool:
    return isinstance(x, Real) and not isinstance(x, bool)
