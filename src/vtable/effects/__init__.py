"""Effects: named pieces of physics a model of the table can add (docs/effects.md).

Each catalog effect is one module here (`vtable.effects.pitch_flexibility`, ...), an
`Effect` object that knows how it enters the reduced model and the virtual table; users
add their own the same way and `register` them (or `vtable ... --effects-from FILE`).
"""

from vtable.effects.base import Assembly, Effect, Param
from vtable.effects.registry import BUILT_IN, get, is_user, load_file, names, register

__all__ = ["BUILT_IN", "Assembly", "Effect", "Param", "get", "is_user", "load_file", "names",
           "register"]
