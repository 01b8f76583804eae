"""Which assembly verbs an effect calls, read from its hooks' source (`ast`): `register`
refuses an effect whose `apply` calls a verb one model cannot realise, naming the verb,
instead of letting it fail on one side at run time."""

from __future__ import annotations

import ast
import inspect
import textwrap

from vtable.effects.base import Assembly, Effect
from vtable.errors import VtableError


def called_verbs(method) -> set[str]:
    """Names `m.<verb>(...)` called on the hook's assembly argument (empty when the source
    cannot be read)."""
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(method)))
    except (OSError, TypeError, SyntaxError):
        return set()
    fn = tree.body[0]
    if not isinstance(fn, ast.FunctionDef) or len(fn.args.args) < 2:
        return set()
    arg = fn.args.args[1].arg
    return {n.func.attr for n in ast.walk(fn) if isinstance(n, ast.Call)
            and isinstance(n.func, ast.Attribute) and isinstance(n.func.value, ast.Name)
            and n.func.value.id == arg}


def _methods(cls) -> set[str]:
    return {k for k in dir(cls) if not k.startswith("_") and callable(getattr(cls, k))}


def check_verbs(e: Effect, where: str) -> None:
    """Every verb an effect's hooks (`apply`, `reduced`, `virtual`) call is one of the
    assembly vocabulary (`Assembly`), which both models implement completely (a test holds
    them to it), so an effect registered here runs in both."""
    known = _methods(Assembly)
    models = {"apply": "both models", "reduced": "the reduced model",
              "virtual": "the virtual table"}
    for hook, model in models.items():
        method = getattr(type(e), hook)
        if method is getattr(Effect, hook):
            continue
        for verb in sorted(called_verbs(method)):
            if verb not in known:
                raise VtableError(
                    f"{where}: effect {e.name!r} calls m.{verb}() in {hook}(), which "
                    f"{model} cannot realise (the verbs: {', '.join(sorted(known))})")
