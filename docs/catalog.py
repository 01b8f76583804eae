"""Print the effect catalog of docs/effects.md from the registry (Markdown).

    python docs/catalog.py [--effects-from FILE ...]
"""

from __future__ import annotations

import sys

from vtable import effects


def _num(x: float) -> str:
    return f"{x:.4g}"


def catalog(users: bool = False) -> str:
    """The catalog's effects (and the registered users' ones when `users`)."""
    out = []
    for name in effects.names():
        if effects.is_user(name) and not users:
            continue
        e = effects.get(name)
        out.append(f"### `{name}`\n")
        out.append(f"- physics: {e.physics}")
        out.append(f"- report: {e.section}")
        out.append(f"- signature: {e.signature}\n")
        if not e.params:
            out.append("No parameters.\n")
            continue
        out.append("| parameter | unit | default | bounds | scale | default from |")
        out.append("|---|---|---|---|---|---|")
        for p in e.params:
            out.append(f"| `{p.name}` | {p.unit} | {_num(p.default)} | "
                       f"{_num(p.lower)} – {_num(p.upper)} | {'log' if p.log else 'linear'} | "
                       f"{p.source or '—'} |")
        out.append("")
    return "\n".join(out)


if __name__ == "__main__":
    args = sys.argv[1:]
    while args:
        flag, path, *args = args
        if flag != "--effects-from":
            raise SystemExit(f"unknown argument {flag!r}")
        effects.load_file(path)
    print(catalog(users=True))
