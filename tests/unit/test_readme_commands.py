"""Every `vtable` command in the ```bash blocks of the README and of the documentation
site's tutorials and how-to pages runs as written (issues 19 and 33), in the order the
pages give them (the README, then mkdocs.yml's nav), in one folder, with fast settings
(`fast`): shorter runs, one run per diagnosis, one round over one candidate; a command
shown twice runs once. Each must exit 0 and write what it names. The install lines of the
README's first block are what CI itself runs."""

from __future__ import annotations

import glob
import re
import shlex
import shutil
from pathlib import Path

import numpy as np
import pytest
import real_data
from conftest import ROOT, doc_blocks, doc_pages

README = (ROOT / "README.md").read_text()


def readme_commands() -> list[str]:
    """The `vtable ...` lines of the bash blocks of the README, the tutorials and the
    how-to pages (continuations joined, comments dropped), in order, each once (the
    contracts' commands name a user's files: `my_effect.py`)."""
    pages = [p for p in doc_pages() if p.parent.name in ("tutorials", "how-to")
             or p.name == "README.md"]
    out = []
    for _, block in doc_blocks("bash", pages):
        for line in block.replace("\\\n", " ").splitlines():
            line = re.sub(r"\s+", " ", line.split("  #")[0].strip())
            if line.startswith("vtable ") and line not in out:
                out.append(line)
    return out


def shortest(runs: list[str]) -> str:
    """Of a diagnosis's run files, the shortest (its CSV the smallest)."""
    return min(runs, key=lambda p: Path(p).with_suffix(".csv").stat().st_size)


def fast(argv: list[str]) -> list[str]:
    """The fast settings: 4 s simulations where the README gives no duration (a record
    is played whole: the test's is short); diagnoses and comparisons on the campaign's
    shortest run; a diagnosis of one round over one candidate, the base as declared."""
    verb = argv[0]
    if verb == "simulate" and "--duration" not in argv and "--record" not in argv:
        argv += ["--duration", "4"]
    if verb in ("diagnose", "compare"):  # one run of the campaign: the shortest
        runs = [a for a in argv if a.endswith(".toml") and not a.startswith("examples/")]
        keep = shortest(runs)
        argv = [a for a in argv if a not in runs or a == keep]
    if verb == "diagnose":  # one cheap candidate; a user effect's own diagnosis is
        # tests/acceptance/test_user_effects.py's
        # (test_with_the_file_it_ranks_first_and_closes_the_gap,
        # test_diagnose_ranks_the_valve_overlap_and_the_error_falls): here its file loads
        argv += ["--effects", "pitch_flexibility", "--max-rounds", "1", "--calibrate", "none"]
    return argv


def write_at2(path: Path, dt: float = 0.01, seconds: float = 6.0) -> None:
    """A PEER NGA .AT2 record (4 header lines, then acceleration in g, 5 per line): a
    2 Hz sine burst under a Hann window."""
    t = np.arange(0.0, seconds, dt)
    acc = 0.2 * np.sin(2 * np.pi * 2.0 * t) * np.hanning(t.size)
    rows = [" ".join(f"{v:.7E}" for v in acc[i:i + 5]) for i in range(0, acc.size, 5)]
    path.write_text("PEER NGA STRONG MOTION DATABASE RECORD\nA test record, 2 Hz burst\n"
                    "ACCELERATION TIME SERIES IN UNITS OF G\n"
                    f"NPTS=  {acc.size}, DT=   {dt:.4f} SEC\n" + "\n".join(rows) + "\n")


def test_the_readme_names_the_commands_it_shows():
    cmds = readme_commands()
    verbs = {shlex.split(c)[1] for c in cmds}
    assert {"simulate", "export-mjcf", "presets", "modes", "margins", "tf", "identify",
            "diagnose", "compare", "drive"} <= verbs, verbs


def test_every_readme_command_runs(tmp_path, monkeypatch, capsys):
    from vtable.cli import main

    monkeypatch.chdir(tmp_path)
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    write_at2(tmp_path / "my_record.AT2")
    model = next(b for _, b in doc_blocks("toml") if b.startswith('model = "hybrid"'))
    if real_data.folder() is not None:  # LNEC's measured run, for the lab-table tutorial
        real_data.copy_run(tmp_path)
    (tmp_path / "my_model.toml").write_text(model)
    t = np.arange(0, 6, 0.005)  # my_motion.csv: a 2 Hz burst, 1 in peak
    x = np.sin(2 * np.pi * 2 * t) * np.sin(np.pi * t / 6) ** 2
    np.savetxt(tmp_path / "my_motion.csv", np.column_stack([t, x]), delimiter=",",
               header="time,displacement", comments="", fmt="%.6f")
    for line in readme_commands():
        if "lnec_pink_2" in line and real_data.folder() is None:
            continue  # the measured run is not beside this checkout (real_data.NEEDED)
        if "lab/run_with_drive.toml" in line:  # the lab's run of the first drive: here the
            (tmp_path / "lab").mkdir(exist_ok=True)  # drive's own run file stands for it
            for ext in (".toml", ".csv"):
                shutil.copy(tmp_path / f"drive/elcentro{ext}",
                            tmp_path / f"lab/run_with_drive{ext}")
        argv = shlex.split(line)[1:]
        argv = [a for pat in argv for a in (sorted(glob.glob(pat)) if "*" in pat else [pat])]
        code = main(fast(argv))
        out, err = capsys.readouterr()
        assert code == 0, f"{line}\n{err}"
        # a page's own example asks nothing of the table it is not rated for (issue 33: the
        # README's first simulate line played 0-25 Hz on the 0-20 Hz table)
        assert "beyond the table's" not in out + err, f"{line}\n{out}{err}"
        for flag in ("--out", "--json", "--rerun", "--report", "--png"):
            if flag in argv and argv[argv.index(flag) + 1:]:
                target = argv[argv.index(flag) + 1]
                if flag == "--out" and argv[0] == "simulate":
                    target += ".toml"
                if flag != "--out" or argv[0] in ("simulate", "export-mjcf"):
                    assert Path(target).exists(), f"{line}: {target} not written"
    # what the commands made, read back: the random run and its noisy sibling
    from vtable.runs import read_run

    noisy, clean = read_run("runs/noisy.toml"), read_run("runs/sdof_random.toml")
    assert clean.time[-1] == pytest.approx(11.0, abs=0.01)
    assert set(noisy.channels) == set(clean.channels)
