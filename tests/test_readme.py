"""The README's examples run as written."""

import re
from pathlib import Path

README = (Path(__file__).resolve().parents[1] / "README.md").read_text()


def test_custom_controller_example_runs(capsys):
    blocks = re.findall(r"```python\n(.*?)```", README, re.S)
    example = next(b for b in blocks if "class SpringBackHorizontal" in b)
    assert len(example.splitlines()) < 45
    exec(compile(example, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert out.startswith("peak pitch ") and float(out.split()[2]) > 0


def test_readme_opens_with_the_two_commands():
    head = README.split("\n## ")[0]
    assert "python -m pip install . && vtable demo" in head
    assert 'python -m pip install -e ".[test]" && python -m pytest -q' in head
    ci = (Path(__file__).resolve().parents[1] / ".ci" / "run").read_text()
    assert 'python -m pip install -q -e ".[test]" && python -m pytest -q' in ci


def test_the_demo_prints_what_the_readme_shows():
    from vtable.verbs.simulation import demo

    block = README.split("## What `vtable demo` shows")[1].split("```\n")[1]
    out = demo(simulate_too=False).report()
    for line in block.splitlines():
        assert line in out.splitlines(), line
    assert "Table 9.2: 2.5391 Hz, 0.0401" in out
