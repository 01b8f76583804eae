"""How much a user's force law costs in the reduced model: the README's backlash effect
(examples/swivel_backlash.py) compiled by numba (automatic when the law is plain Python
numba can type) against the same law run as Python, and the base model without it.

Prints seconds per simulation of an 11 s run at 200 Hz (one fit evaluates the model
~50-250 times).
"""

from __future__ import annotations

import time
from pathlib import Path

from vtable.effects import load_file, register
from vtable.effects.registry import get
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.params import presets
from vtable.signals import make_command
from vtable.sim import simulate

ROOT = Path(__file__).resolve().parents[1]


def best(f, repeat=3) -> float:
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return min(out)


def main() -> None:
    load_file(ROOT / "examples" / "swivel_backlash.py")
    example = get("swivel_backlash")

    class PythonOnly:
        def __init__(self, m):
            self.m = m

        def __getattr__(self, name):  # everything else (m.table, ...) from the assembly
            return getattr(self.m, name)

        def insert_at_actuators(self, name, mass, law, params, states=0, stiffness=0.0):
            def python_law(d, v, z, p, dz):  # a dict: numba cannot type it
                return {"f": law(d, v, z, p, dz)}["f"]

            self.m.insert_at_actuators(name, mass, python_law, params, states, stiffness)

    class Slow(type(example)):
        name = "swivel_backlash_python"

        def apply(self, m, p):
            example.apply(PythonOnly(m), p)

    register(Slow())
    spec = presets.specimen("sdof_frame")
    cmd = make_command("random", duration=11.0, band=(0.0, 25.0), peak_in=0.05, seed=1)
    base = Physics(nominal_open_loop(), spec, {})
    run = simulate(base, cmd)
    t, x = run.time, run.channel("h_span")
    rows = []
    for label, effects in (("base model", {}),
                           ("+ backlash, law compiled by numba", {"swivel_backlash": {}}),
                           ("+ backlash, law run as Python", {"swivel_backlash_python": {}})):
        import warnings

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            model = ReducedModel(Physics(nominal_open_loop(), spec, effects))
        t0 = time.perf_counter()
        model.simulate(t, x)  # compiles on first use
        first = time.perf_counter() - t0
        rows.append((label, first, best(lambda m=model: m.simulate(t, x), 1 if
                                        "Python" in label else 3)))
    print(f"reduced model, 11 s run at 200 Hz ({len(t)} samples):")
    for label, first, b in rows:
        print(f"  {label:<36} {b:8.3f} s per simulation (first call {first:.1f} s)")
    print(f"  Python law / compiled law: {rows[2][2] / rows[1][2]:.0f}x slower")


if __name__ == "__main__":
    main()
