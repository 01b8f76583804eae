"""The README is a front door (issue 33): short, the two set-up commands first, a quick
start; the examples of the README and of the documentation site run as written."""

import re
import subprocess
import sys
from pathlib import Path

from conftest import ROOT, doc_blocks, doc_pages

README = (ROOT / "README.md").read_text()


def test_the_readme_is_short_and_links_every_tutorial():
    assert len(README.splitlines()) <= 150
    quick = README.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    cmds = [ln for ln in quick.replace("\\\n", " ").splitlines() if ln.startswith("vtable ")]
    assert [c.split()[1] for c in cmds] == ["simulate"] * 3 + ["diagnose"], cmds
    assert all("--effect actuator_friction:friction=3" in c for c in cmds[:3]), cmds
    for page in (ROOT / "docs" / "tutorials").glob("*.md"):
        assert f"(docs/tutorials/{page.name})" in README, page.name


def test_the_site_builds_without_a_warning(tmp_path):
    """`mkdocs build --strict`: a broken link, a page outside the nav or a docstring the
    API reference cannot read fails the build."""
    out = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d",
                          str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True,
                         env={"NO_MKDOCS_2_WARNING": "1", "PATH": "/usr/bin:/bin",
                              "HOME": str(tmp_path)})
    assert out.returncode == 0, out.stderr[-3000:]
    api = (tmp_path / "site" / "api" / "index.html").read_text()
    for name in ("vtable.verbs.diagnose", "vtable.diagnose.Diagnoser", "vtable.effects.Effect",
                 "vtable.runs.read_run"):
        assert f'id="{name}"' in api, name
    pages = {p.relative_to(ROOT / "docs").with_suffix("").as_posix() for p in doc_pages()[1:]}
    for page in pages:
        html = tmp_path / "site" / ("" if page == "index" else page) / "index.html"
        assert html.is_file(), page


def test_custom_controller_example_runs(capsys):
    example = next(b for _, b in doc_blocks("python") if "class SpringBackHorizontal" in b)
    assert len(example.splitlines()) < 45
    exec(compile(example, "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert out.startswith("peak pitch ") and float(out.split()[2]) > 0


def test_readme_opens_with_the_two_commands():
    head = README.split("\n## ")[0]
    assert "python -m pip install . && vtable demo" in head
    assert 'python -m pip install -e ".[test]" && python -m pytest -q' in head
    ci = (Path(__file__).resolve().parents[2] / ".ci" / "run").read_text()
    assert 'python -m pip install -q -e ".[test]" && python -m pytest -q' in ci


def test_the_demo_prints_what_the_readme_shows():
    from vtable.verbs.simulation import demo

    page = (ROOT / "docs" / "tutorials" / "virtual-table.md").read_text()
    block = page.split("## What `vtable demo` shows")[1].split("```\n")[1]
    out = demo(simulate_too=False).report()
    for line in block.splitlines():
        assert line in out.splitlines(), line
    assert "Table 9.2: 2.5391 Hz, 0.0401" in out


def test_the_readme_images_exist_and_show_something():
    """Every image the README shows is in the repository, and none is blank (a screenshot
    taken before the page drew is one colour: issue 19's screenshots must show plots)."""
    import matplotlib.image as mpimg
    import numpy as np

    images = {(p.parent / rel).resolve().relative_to(ROOT).as_posix()
              for p in doc_pages()
              for rel in re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", p.read_text())}
    assert {"docs/img/screenshot_rerun.png", "docs/img/screenshot_report_tf.png",
            "docs/img/screenshot_report_time.png"} <= images, images
    for rel in images:
        px = mpimg.imread(ROOT / rel)[..., :3]
        assert px.shape[0] > 300 and px.shape[1] > 500, (rel, px.shape)
        # more than 2 % of the pixels differ from the most common colour by a visible step
        flat = px[::3, ::3].reshape(-1, 3)
        vals, counts = np.unique((flat * 255).round().astype(int), axis=0, return_counts=True)
        mode = vals[counts.argmax()] / 255
        assert np.mean(np.abs(flat - mode).max(axis=1) > 0.1) > 0.02, f"{rel} looks blank"


def test_every_python_block_of_the_pages_runs(tmp_path, monkeypatch):
    """Every ```python block of the README, the tutorials and the how-to pages runs as
    written, in a folder of its own (one shown verbatim from examples/ is that file: its own
    tests load and diagnose it; the contracts' fragments are excerpts, not programs)."""
    examples = {p.read_text() for p in (ROOT / "examples").glob("*.py")}
    pages = [p for p in doc_pages() if p.parent.name in ("tutorials", "how-to")
             or p.name == "README.md"]
    monkeypatch.chdir(tmp_path)
    ran = 0
    for page, block in doc_blocks("python", pages):
        if block in examples:
            continue
        exec(compile(block, str(page.relative_to(ROOT)), "exec"), {"__name__": "__doc__"})
        ran += 1
    assert ran >= 4, ran  # the how-to's three and the custom controller
    assert (tmp_path / "diagnosis.html").stat().st_size > 10_000  # the how-to's report
