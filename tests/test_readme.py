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


def test_the_readme_images_exist_and_show_something():
    """Every image the README shows is in the repository, and none is blank (a screenshot
    taken before the page drew is one colour: issue 19's screenshots must show plots)."""
    import matplotlib.image as mpimg
    import numpy as np

    root = Path(__file__).resolve().parents[1]
    images = re.findall(r"!\[[^\]]*\]\((docs/img/[^)]+\.png)\)", README)
    assert {"docs/img/screenshot_rerun.png", "docs/img/screenshot_report_tf.png",
            "docs/img/screenshot_report_time.png"} <= set(images), images
    for rel in images:
        px = mpimg.imread(root / rel)[..., :3]
        assert px.shape[0] > 300 and px.shape[1] > 500, (rel, px.shape)
        # more than 2 % of the pixels differ from the most common colour by a visible step
        flat = px[::3, ::3].reshape(-1, 3)
        vals, counts = np.unique((flat * 255).round().astype(int), axis=0, return_counts=True)
        mode = vals[counts.argmax()] / 255
        assert np.mean(np.abs(flat - mode).max(axis=1) > 0.1) > 0.02, f"{rel} looks blank"
