"""Issue 10: effects as objects, and a user's own effect in the loop.

The README's user effect (backlash in the horizontal actuators' swivels) is the file
examples/swivel_backlash.py, outside the package; these tests load it as a user would.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import campaign_commands

from vtable.cli import main
from vtable.effects import BUILT_IN, get, load_file, names
from vtable.effects.physics import Physics, nominal_open_loop
from vtable.params import presets
from vtable.sim import simulate

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "swivel_backlash.py"
GAP_IN = 0.005  # the hidden backlash: 5 mils of free play


def test_the_readme_shows_the_example_file_whole_and_short():
    text = EXAMPLE.read_text()
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    assert text in blocks, "the README must show examples/swivel_backlash.py verbatim"
    assert len(text.splitlines()) <= 40


def test_loading_registers_it_next_to_the_catalog():
    assert load_file(EXAMPLE) == ["swivel_backlash"]
    assert "swivel_backlash" in names() and set(BUILT_IN) <= set(names())
    e = get("swivel_backlash")
    assert e.param("gap").unit == "in" and e.param("gap").log


def _grep(pattern: str, skip) -> list[str]:
    hits = []
    for folder in ("src/vtable", "controllers", "viz"):
        for f in (ROOT / folder).rglob("*.py"):
            if skip(f):
                continue
            for i, line in enumerate(f.read_text().splitlines(), 1):
                if re.search(pattern, line):
                    hits.append(f"{f.relative_to(ROOT)}:{i}: {line.strip()}")
    return hits


@pytest.mark.parametrize("name", BUILT_IN)
def test_no_effect_name_is_tested_outside_its_own_file(name):
    own = {f"{name}.py", "registry.py"}
    tests = (rf'has\(\s*["\']{name}["\']|==\s*["\']{name}["\']|["\']{name}["\']\s*(==|in\b)'
             rf'|\[\s*["\']{name}["\']\s*\]|get\(\s*["\']{name}["\']')
    assert _grep(tests, lambda f: f.name in own) == []


def test_no_numbered_servo_slots_outside_the_hydraulic_element():
    slots = r"\bsp\[\s*(\d|_?[A-Z]+\b)|servo_vector|\bN_SERVO\b"
    assert _grep(slots, lambda f: f.name == "element.py" and f.parent.name == "hydraulics") == []


@pytest.mark.parametrize("source, msg", [
    ("x = (\n", "line 1: syntax error"),
    ("from vtable.effects import Effect, Param, register\n"
     "class E(Effect):\n    name = 'bad_bounds'\n    physics = section = signature = 'x'\n"
     "    params = (Param('a', 'in', 1.0, 2.0, 5.0),)\n"
     "    def apply(self, m, p):\n        pass\nregister(E())\n",
     "default 1.0 is outside its bounds [2, 5] in"),
    ("from vtable.effects import Effect, Param, register\n"
     "class E(Effect):\n    name = 'no_bounds'\n    physics = section = signature = 'x'\n"
     "    params = (Param('a', 'in', 1.0),)\n"
     "    def apply(self, m, p):\n        pass\nregister(E())\n",
     "TypeError while loading"),
    ("from vtable.effects import Effect, Param, register\n"
     "class E(Effect):\n    name = 'sensor_filter'\n    physics = section = signature = 'x'\n"
     "    def apply(self, m, p):\n        pass\nregister(E())\n",
     "clashes with a built-in effect"),
    ("from vtable.effects import Effect, Param, register\n"
     "class E(Effect):\n    name = 'lazy'\n    physics = section = signature = 'x'\n"
     "register(E())\n", "defines neither apply"),
    ("x = 1\n", "registers no effect"),
])
def test_a_bad_effect_file_is_one_line_naming_it(capsys, tmp_path, source, msg):
    f = tmp_path / "my_effects.py"
    f.write_text(source)
    code = main(["simulate", "--duration", "1", "--effects-from", str(f)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert str(f) in err and msg in err, err


@functools.cache
def backlash_campaign():
    load_file(EXAMPLE)
    truth = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                    {"swivel_backlash": {"gap": GAP_IN}})
    runs = [simulate(truth, c, noise=0.01, seed=10 + i, name=f"run{i}")
            for i, c in enumerate(campaign_commands())]
    return truth, runs


def test_without_the_file_the_residual_is_unexplained():
    """No built-in effect is claimed to explain backlash: nothing is added and the verdict
    says a residual remains, where (table acceleration, small spans)."""
    from vtable.diagnose.engine import Diagnoser

    _, runs = backlash_campaign()
    d = Diagnoser(runs, catalog=BUILT_IN).diagnose()
    assert d.final_effects == []
    assert d.unexplained is not None and d.unexplained["ratio_to_floor"] > 5
    assert "a residual remains unexplained" in d.verdict
    assert "smallest spans" in d.unexplained["where"]


def test_with_the_file_it_ranks_first_and_closes_the_gap():
    from vtable.diagnose.engine import Diagnoser

    truth, runs = backlash_campaign()
    d = Diagnoser(runs, max_rounds=1).diagnose()
    best = d.rounds[0].ranking[0]
    assert best.effect == "swivel_backlash" and d.rounds[0].added == "swivel_backlash"
    true_err = Diagnoser(runs, catalog=[]).score(truth).error
    assert best.error_after <= 1.5 * true_err, (best.error_after, true_err)
    assert best.params["gap"] == pytest.approx(GAP_IN, rel=0.2)
    assert d.unexplained is None
    j = d.to_json()  # it appears in the JSON like a catalog effect
    assert j["final_effects"] == ["swivel_backlash"]
    assert j["rounds"][0]["ranking"][0]["params"]["gap"] == pytest.approx(GAP_IN, rel=0.2)


def test_a_pure_python_law_gives_the_same_prediction():
    """numba is an option: a law numba cannot compile runs as Python, same numbers."""
    from vtable.effects import register
    from vtable.effects.reduced import ReducedModel

    truth, runs = backlash_campaign()
    r = runs[0]
    example = get("swivel_backlash")

    class PythonOnly:
        """The example's effect, its law wrapped in Python numba cannot type."""

        def __init__(self, m):
            self.m = m

        def insert_at_actuators(self, name, mass, law, params, states=0, stiffness=0.0):
            def python_law(d, v, z, p, dz):
                return {"f": law(d, v, z, p, dz)}["f"]

            self.m.insert_at_actuators(name, mass, python_law, params, states, stiffness)

    class Slow(type(example)):
        name = "swivel_backlash_python"

        def apply(self, m, p):
            example.apply(PythonOnly(m), p)

    register(Slow())
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                 {"swivel_backlash_python": {"gap": GAP_IN}})
    with pytest.warns(RuntimeWarning, match="runs as Python"):
        model = ReducedModel(ph)
    assert model.python
    part = slice(0, 300)
    slow = model.simulate(r.time[part], r.channel("h_span")[part])
    quick = ReducedModel(truth).simulate(r.time[part], r.channel("h_span")[part])
    for ch in ("avg_hdisp", "avg_hacc", "acc_n_ne"):
        np.testing.assert_allclose(slow[ch], quick[ch], rtol=1e-7,
                                   atol=1e-9 * np.max(np.abs(quick[ch])))
