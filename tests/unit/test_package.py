"""The design card's layout: controllers/ and viz/ are vtable.controllers / vtable.viz."""

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_editable_install_maps_subpackages():
    import vtable.controllers
    import vtable.viz

    assert Path(vtable.controllers.__file__).parent.name == "controllers"
    assert Path(vtable.viz.__file__).parent.name == "viz"


def test_no_top_level_controllers_or_viz():
    r = subprocess.run([sys.executable, "-c", "import controllers"], capture_output=True,
                       cwd="/", text=True)
    assert r.returncode != 0
    r = subprocess.run([sys.executable, "-c", "import viz"], capture_output=True, cwd="/",
                       text=True)
    assert r.returncode != 0


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    out = tmp_path_factory.mktemp("wheel")
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out),
                        str(ROOT)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    (whl,) = out.glob("vtable-*.whl")
    return whl


def test_wheel_contains_the_layout(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    for need in ("vtable/controllers/__init__.py", "vtable/viz/__init__.py",
                 "vtable/assets/records/elcentro_1940_ns.csv", "vtable/params/data/eerc.toml",
                 "vtable/params/data/models.toml", "vtable/params/data/specimens.toml",
                 "vtable/cli.py"):
        assert need in names, need
    assert not any(n.startswith(("controllers/", "viz/", "tests/")) for n in names)


def test_wheel_holds_every_package(wheel):
    """Every folder with an __init__.py under src/, controllers/ and viz/ is in the wheel
    (a subpackage missing from pyproject's list broke `pip install .` once)."""
    names = set(zipfile.ZipFile(wheel).namelist())
    roots = {ROOT / "src" / "vtable": "vtable", ROOT / "controllers": "vtable/controllers",
             ROOT / "viz": "vtable/viz"}
    for root, inside in roots.items():
        for init in root.rglob("__init__.py"):
            rel = init.relative_to(root).as_posix()
            assert f"{inside}/{rel}" in names, f"{inside}/{rel}"


def test_normal_install_runs(wheel, tmp_path):
    target = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target",
                        str(target), str(wheel)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    code = ("import vtable, vtable.controllers, vtable.viz;"
            "from vtable.params import presets; from vtable.signals import el_centro;"
            f"assert vtable.__file__.startswith({str(target)!r}), vtable.__file__;"
            "assert len(el_centro().acc) == 3995; presets.eerc_table();"
            "from vtable.cli import main; raise SystemExit(main(['modes']))")
    env = {**os.environ, "PYTHONPATH": str(target)}
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
                       env=env, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "2.5402" in r.stdout


def test_numba_cache_never_inside_the_installed_package(wheel, tmp_path):
    """Issue 9: `vtable demo` after `pip install .` left numba's cache inside the installed
    package, and that leftover folder shadowed a later editable install. The compiled
    kernels must be cached in the user's cache folder instead."""
    target = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target",
                        str(target), str(wheel)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    cache = tmp_path / "xdg"
    code = ("import numpy as np; from vtable.signals.spectra import response_spectrum;"
            "s = response_spectrum(np.sin(np.arange(400) * 0.1), 0.01, np.array([0.5]), 0.05);"
            "print(float(s.psa[0]) > 0)")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update({"PYTHONPATH": str(target), "XDG_CACHE_HOME": str(cache)})
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
                       env=env, timeout=300)
    assert r.returncode == 0 and "True" in r.stdout, r.stderr[-2000:]
    inside = [p for p in (target / "vtable").rglob("*") if p.suffix in (".nbi", ".nbc")]
    assert inside == []
    assert list((cache / "vtable" / "numba").rglob("*.nbi"))  # the cache went here
