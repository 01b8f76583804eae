"""The effects a verb's arguments name: the user's effect files registered, and a
comma-separated list checked against the registry; the user's controller files registered."""

from __future__ import annotations

from collections.abc import Sequence

from vtable.controllers import kinds
from vtable.effects import load_file
from vtable.effects.registry import get


def load_effects(files: Sequence[str]) -> list[str]:
    """Register the effects of the user's files; their names."""
    return [n for f in files for n in load_file(f)]


def load_controllers(files: Sequence[str]) -> list[str]:
    """Register the controller kinds of a lab's files (`--controller-from`); their names."""
    return [n for f in files for n in kinds.load_file(f)]


def effect_names(text: str) -> list[str]:
    """'a, b' -> ["a", "b"], each a registered effect."""
    names = [e.strip() for e in text.split(",") if e.strip()]
    for e in names:
        get(e)
    return names
