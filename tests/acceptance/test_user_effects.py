"""Issue 10: effects as objects, and a user's own effect in the loop.

The README's user effect (backlash in the horizontal actuators' swivels) is the file
examples/swivel_backlash.py, outside the package; these tests load it as a user would.
"""

from __future__ import annotations

import functools
import math
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import campaign_commands, doc_blocks

from vtable.cli import main
from vtable.effects import BUILT_IN, Effect, Param, get, load_file, names
from vtable.models.physics import Physics, nominal_open_loop
from vtable.params import presets
from vtable.sim import simulate

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "swivel_backlash.py"
VALVE = ROOT / "examples" / "valve_overlap.py"
GAP_IN = 0.005  # the hidden backlash: 5 mils of free play
OVERLAP_PCT = 0.5  # the hidden spool overlap: 0.5 % of the stroke


def test_the_readme_shows_the_example_file_whole_and_short():
    text = EXAMPLE.read_text()
    blocks = [b for _, b in doc_blocks("python")]
    assert text in blocks, "the own-effect tutorial must show examples/swivel_backlash.py"
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


def backlash_campaign():
    """The backlash campaign, its effect loaded (each test starts from the catalog as
    shipped: conftest's catalog_as_shipped)."""
    load_file(EXAMPLE)
    return _backlash_campaign()


@functools.cache
def _backlash_campaign():
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
    d = Diagnoser(runs, catalog=BUILT_IN).diagnose()  # the catalog, storey_yield included
    assert d.final_effects == []
    assert d.unexplained is not None and d.unexplained["ratio_to_floor"] > 5
    assert "a residual remains unexplained" in d.verdict
    assert "smallest spans" in d.unexplained["where"]
    # every catalog effect was a candidate (backlash shows amplitude dependence: the
    # nonlinear ones were fitted, the yielding storey among them), none claimed it
    tried = {c.effect for c in d.rounds[0].ranking} | set(d.rounds[0].skipped)
    assert tried == set(BUILT_IN), tried
    assert not any(c.not_fitted for c in d.rounds[0].ranking)


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


def _example_with_law(name: str, make_law):
    """The README's example effect (loaded: `backlash_campaign`) under another `name`, its
    force law replaced by `make_law(its law)`; the rest of the assembly as it is."""
    example = get("swivel_backlash")

    class Wrapped:
        def __init__(self, m):
            self.m = m

        def __getattr__(self, attr):  # the rest of the assembly (m.table, ...) as it is
            return getattr(self.m, attr)

        def insert_at_actuators(self, part, mass, law, params, states=0, stiffness=0.0):
            self.m.insert_at_actuators(part, mass, make_law(law), params, states, stiffness)

    class Made(type(example)):
        def apply(self, m, p):
            example.apply(Wrapped(m), p)

    Made.name = name
    return Made()


def test_a_pure_python_law_gives_the_same_prediction():
    """numba is an option: a law numba cannot compile runs as Python, same numbers."""
    from vtable.effects import register
    from vtable.models.reduced import ReducedModel

    truth, runs = backlash_campaign()
    r = runs[0]

    def python_only(law):  # the example's law wrapped in Python numba cannot type
        def python_law(d, v, z, p, dz):
            return {"f": law(d, v, z, p, dz)}["f"]

        return python_law

    register(_example_with_law("swivel_backlash_python", python_only))
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                 {"swivel_backlash_python": {"gap": GAP_IN}})
    with pytest.warns(RuntimeWarning, match="runs as Python") as caught:
        model = ReducedModel(ph)
    # the warning names the law, its file and numba's reason
    msg = str(caught[0].message)
    assert "python_law (" in msg and "test_user_effects.py" in msg and "Error" in msg, msg
    assert model.python
    part = slice(0, 300)
    slow = model.simulate(r.time[part], r.channel("h_span")[part])
    quick = ReducedModel(truth).simulate(r.time[part], r.channel("h_span")[part])
    for ch in ("avg_hdisp", "avg_hacc", "acc_n_ne"):
        np.testing.assert_allclose(slow[ch], quick[ch], rtol=1e-7,
                                   atol=1e-9 * np.max(np.abs(quick[ch])))


def test_a_law_that_allocates_runs_compiled_with_the_same_prediction():
    """The integrators' loops are compiled without numba's reference counting, which a
    law that makes an array cannot be compiled into: such a law gets the loops compiled
    with it (`compose.counted`), not Python, and predicts what the catalog's law does."""
    import math
    import warnings

    from vtable.effects import register
    from vtable.effects.valve_flow_nonlinearity import ValveFlowNonlinearity
    from vtable.hydraulics.stage import Stage
    from vtable.models.reduced import ReducedModel

    def allocating_orifice(q, P, p):
        s = np.zeros(1)  # an array made on every call
        s[0] = 1.0 - (P if q >= 0 else -P) / p.supply_pressure
        return q * math.sqrt(s[0]) if s[0] > 0 else 0.0

    stage = Stage("orifice_allocating", "flow", allocating_orifice, ("supply_pressure",),
                  order=1.0)

    class Made(ValveFlowNonlinearity):
        name = "valve_flow_allocating"

        def apply(self, m, p):
            m.add_stage(stage, supply_pressure=p["supply_pressure"])

    register(Made())
    _, runs = backlash_campaign()
    r = runs[0]
    part = slice(0, 300)
    spec = presets.specimen("sdof_frame")
    made_ph = Physics(nominal_open_loop(), spec, {"valve_flow_allocating": {}})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # compiled: no "runs as Python"
        model = ReducedModel(made_ph)
        assert model.element.key.endswith("u")  # first the uncounted loops ...
        made = model.simulate(r.time[part], r.channel("h_span")[part])
    assert not model.python and model.element.key.endswith("c"), model.element.key  # ... then
    catalog = ReducedModel(Physics(nominal_open_loop(), spec, {"valve_flow_nonlinearity": {}}))
    assert catalog.element.key.endswith("u")  # the catalog's law: uncounted
    quick = catalog.simulate(r.time[part], r.channel("h_span")[part])
    assert np.max(np.abs(quick["avg_hdisp"])) > 0
    for ch in ("avg_hdisp", "avg_hacc", "h1_force"):
        np.testing.assert_array_equal(made[ch], quick[ch])
    # a model built again on that law goes straight to the counted element
    assert ReducedModel(made_ph).element is model.element


def _allocating_dead_band(d, v, z, p, dz):
    """The example's dead band (examples/swivel_backlash.py), its terms in an array made on
    every call."""
    half = 0.5 * p.gap
    f = np.zeros(2)
    f[0] = -p.k * (d - half * math.tanh(d / half))
    f[1] = -p.c * math.tanh(d / half) ** 2 * v
    return f[0] + f[1]


def test_a_force_law_that_allocates_runs_compiled_with_the_same_prediction():
    """A force law that makes an array is compiled too (with the reference counting, in its
    own function or in the counted loops), not run as Python, and predicts what the
    example's law does."""
    import warnings

    from vtable.effects import register
    from vtable.models.reduced import ReducedModel

    truth, runs = backlash_campaign()
    r = runs[0]
    register(_example_with_law("swivel_backlash_allocating", lambda law: _allocating_dead_band))
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                 {"swivel_backlash_allocating": {"gap": GAP_IN}})
    part = slice(0, 300)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # compiled: no "runs as Python"
        model = ReducedModel(ph)
        made = model.simulate(r.time[part], r.channel("h_span")[part])
    assert not model.python and model.elem is not None
    quick = ReducedModel(truth).simulate(r.time[part], r.channel("h_span")[part])
    assert np.max(np.abs(quick["avg_hdisp"])) > 0
    for ch in ("avg_hdisp", "avg_hacc", "acc_n_ne"):
        np.testing.assert_array_equal(made[ch], quick[ch])


def test_every_effect_calls_only_verbs_both_models_realise():
    """The catalog's and the examples' effects pass the check `register` makes."""
    from vtable.effects.verbs import called_verbs, check_verbs

    load_file(VALVE)
    load_file(EXAMPLE)
    for name in names():
        check_verbs(get(name), name)
    assert called_verbs(type(get("valve_overlap")).apply) == {"add_stage"}
    assert called_verbs(type(get("swivel_backlash")).apply) == {"insert_at_actuators"}


@pytest.mark.parametrize("hook, verb, msg", [
    ("apply", "matrices", "calls m.matrices() in apply(), which both models cannot"),
    ("virtual", "add_link", "calls m.add_link() in virtual(), which the virtual table cannot"),
    ("apply", "set_servo", "calls m.set_servo() in apply(), which both models cannot"),
])
def test_a_verb_one_model_lacks_is_refused_when_registered(capsys, tmp_path, hook, verb, msg):
    other = "" if hook == "apply" else "    def reduced(self, m, p):\n        pass\n"
    f = tmp_path / "springy.py"
    f.write_text("from vtable.effects import Effect, Param, register\n"
                 "class E(Effect):\n    name = 'springy'\n    physics = section = signature = 'x'\n"
                 f"    def {hook}(self, m, p):\n        m.{verb}('x', None, 1.0, 0.0)\n"
                 f"{other}register(E())\n")
    code = main(["simulate", "--duration", "1", "--effects-from", str(f)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert str(f) in err and msg in err, err


class FlexibleLink(Effect):
    """The actuators push a 900 kg link tied to the platen by a spring (12 Hz with the
    link), a dashpot and a quadratic damper: every coordinate verb, in both models."""

    name = "flexible_link"
    physics = section = signature = "a test of the coordinate verbs"
    params = (Param("f_link", "Hz", 12.0, 1.0, 100.0),)

    def apply(self, m, p):
        mass = 900.0
        k = mass * (2 * math.pi * p["f_link"]) ** 2
        m.add_dof("link", mass)
        m.set_actuator(moving="link")
        m.add_spring("link", "x", k, 0.05 * 2 * math.sqrt(k * mass))
        m.add_force(quadratic, "link", "x", [2e5], mass=mass, stiffness=0.0)


def quadratic(d, v, z, p, dz):
    return -p[0] * abs(v) * v


def test_the_coordinate_verbs_agree_in_both_models():
    """add_dof, set_actuator, add_spring and add_force realised on the virtual table
    (MjSpec edits and a force-law controller) as in the reduced model: within 2 %."""
    from vtable.effects import register
    from vtable.models.reduced import ReducedModel

    register(FlexibleLink())
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"), {"flexible_link": {}})
    random, _, quake = campaign_commands()
    for cmd in (random, quake):
        run = simulate(ph, cmd)
        pred = ReducedModel(ph).predict(run)
        base = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame"))
                            ).predict(run)
        for ch in ("avg_hdisp", "avg_hacc", "h1_force", "acc_n_ne"):
            y = run.channel(ch)
            err = np.sqrt(np.mean((pred[ch] - y) ** 2) / np.mean(y**2))
            off = np.sqrt(np.mean((base[ch] - y) ** 2) / np.mean(y**2))
            assert err < 0.02 and off > 5 * err, (cmd.name, ch, err, off)


@pytest.mark.parametrize("verb", ["insert_at_actuators", "add_storey_force"])
def test_a_missing_stiffness_is_worked_out_from_the_law(verb):
    """Without stiffness=, the step follows the law's largest slope (here k = 4e10 N/m on
    the 680 kg pistons, or the SDOF mass), as with it; a law that cannot be probed is one
    line."""
    from vtable.errors import VtableError
    from vtable.models.reduced import ReducedAssembly
    from vtable.models.stiffness import needed_stiffness
    from vtable.tables.eerc import virtual_table

    k = 4e10
    gap_k = {"gap": 0.001, "k": k, "c": 0.0}
    assert needed_stiffness(get_law(), gap_k) == pytest.approx(k, rel=1e-3)
    ph = Physics(nominal_open_loop(), presets.specimen("sdof_frame"))
    steps = []
    for stiffness in (k, None):
        m = ReducedAssembly(ph, virtual_table())
        if verb == "insert_at_actuators":
            m.insert_at_actuators("piston", 680.0, get_law(), {"gap": 0.001, "k": k, "c": 0.0},
                                  stiffness=stiffness)
        else:
            m.add_storey_force(get_law(), {"gap": 0.001, "k": k, "c": 0.0}, stiffness=stiffness)
        steps.append(m.max_step)
    assert steps[1] == pytest.approx(steps[0], rel=1e-3) and steps[0] < 2.5e-3
    with pytest.raises(VtableError, match=r"^raising_law: give stiffness=.*ValueError: no"):
        m.add_storey_force(raising_law, [0.0])
    with pytest.raises(VtableError, match=r"^rigid_law: give stiffness= .* not finite"):
        m.add_storey_force(rigid_law, [0.0])


def get_law():
    load_file(EXAMPLE)
    import sys

    return next(m.dead_band for m in sys.modules.values()
                if getattr(m, "dead_band", None) is not None and hasattr(m, "SwivelBacklash"))


def raising_law(d, v, z, p, dz):
    raise ValueError("no contact model")


def rigid_law(d, v, z, p, dz):
    return -math.inf if d > 0 else 0.0


def test_the_readme_shows_the_valve_example_whole_and_short():
    text = VALVE.read_text()
    blocks = [b for _, b in doc_blocks("python")]
    assert text in blocks, "the own-effect tutorial must show examples/valve_overlap.py"
    assert len(text.splitlines()) <= 40


def test_the_valve_example_simulates_from_the_cli(capsys, tmp_path):
    out = tmp_path / "overlap"
    code = main(["simulate", "--duration", "2", "--effects-from", str(VALVE),
                 "--effect", f"valve_overlap:overlap={OVERLAP_PCT}", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    assert (tmp_path / "overlap.toml").is_file() and (tmp_path / "overlap.csv").is_file()


def overlap_campaign():
    load_file(VALVE)
    return _overlap_campaign()


@functools.cache
def _overlap_campaign():
    truth = Physics(nominal_open_loop(), presets.specimen("sdof_frame"),
                    {"valve_overlap": {"overlap": OVERLAP_PCT}})
    runs = [simulate(truth, c, noise=0.01, seed=20 + i, name=f"run{i}")
            for i, c in enumerate(campaign_commands())]
    return truth, runs


def test_diagnose_ranks_the_valve_overlap_and_the_error_falls():
    from vtable.diagnose.engine import Diagnoser

    truth, runs = overlap_campaign()
    d = Diagnoser(runs, max_rounds=1, catalog=[*BUILT_IN, "valve_overlap"]).diagnose()
    best = d.rounds[0].ranking[0]
    assert best.effect == "valve_overlap" and d.rounds[0].added == "valve_overlap"
    assert best.error_after < 0.5 * d.rounds[0].before, (d.rounds[0].before, best.error_after)
    true_err = Diagnoser(runs, catalog=[]).score(truth).error
    assert best.error_after <= 1.5 * true_err, (best.error_after, true_err)
    assert best.params["overlap"] == pytest.approx(OVERLAP_PCT, rel=0.2)


def test_a_force_law_reads_its_parameters_by_name_in_both_models():
    """A force law given its parameters as a mapping reads them by name (`p.c2`) and gives
    the same forces as the positional law (`p[0]`), in the reduced model and on the virtual
    table's force-law controller."""
    from vtable.controllers.force_law import ForceLawController
    from vtable.models.reduced import ReducedModel
    from vtable.signals import make_command

    def by_name(d, v, z, p, dz):
        return -p.c2 * abs(v) * v - p.k * d

    def by_index(d, v, z, p, dz):
        return -p[0] * abs(v) * v - p[1] * d

    class Storey(Effect):
        name = "storey_law"
        physics = section = signature = "a test"
        params = ()

        def __init__(self, law, params):
            self.law, self.p = law, params

        def apply(self, m, p):
            m.add_storey_force(self.law, self.p, stiffness=2.0e5)

    cmd = make_command("random", duration=4.0, peak_in=0.1)
    out = []
    for e in (Storey(by_name, {"c2": 3.0e4, "k": 2.0e5}), Storey(by_index, [3.0e4, 2.0e5])):
        m = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame")))
        m.assembly.elements.clear()
        e.apply(m.assembly, {})
        m._element(m.assembly.elements)
        m.linear = False
        out.append(m.simulate(cmd.t, cmd.x)["acc_n_ne"])
    np.testing.assert_allclose(out[0], out[1], rtol=1e-12, atol=1e-12)
    base = ReducedModel(Physics(nominal_open_loop(), presets.specimen("sdof_frame")))
    plain = base.simulate(cmd.t, cmd.x)["acc_n_ne"]
    assert np.std(out[0] - plain) > 0.05 * np.std(plain)  # the law acts
    named_ctl = ForceLawController(("S",), by_name, {"c2": 3.0e4, "k": 2.0e5})
    index_ctl = ForceLawController(("S",), by_index, [3.0e4, 2.0e5])
    for c in (named_ctl, index_ctl):
        c.bind(("S",))
    s = np.array([0.001, 0.02])
    assert named_ctl.step(0.001, s, None) == pytest.approx(index_ctl.step(0.001, s, None))
    assert named_ctl.p.k == 2.0e5
