"""What `vtable drive` tells a new user (issue 33): the amplification figures say where the
cap applies and whether it held, the above-band note explains the default correction
band, no cell of the report is `nan`, and the drive's run file says the rest it plays
before its target (`[command] lead_s`)."""

from __future__ import annotations

import functools
import json
import math
import tempfile
import tomllib
from pathlib import Path

import pytest

from vtable.cli import main


@functools.cache
def drive() -> tuple[Path, str, dict]:
    """The README's drive: the SDOF frame's 11 s random run, El Centro at 2 in, with pitch
    (printed report, JSON, run file)."""
    folder = Path(tempfile.mkdtemp(prefix="vtable-drive-report-"))
    run = folder / "sdof_random"
    assert main(["simulate", "--specimen", "sdof_frame", "--command", "random", "--band", "0",
                 "20", "--peak", "0.25", "--duration", "11", "--out", str(run)]) == 0
    stem = folder / "drive"
    assert main(["drive", f"{run}.toml", "--target", "elcentro", "--target-peak", "2",
                 "--with", "pitch_flexibility", "--out", str(stem), "--json",
                 f"{stem}.json"]) == 0
    from vtable import verbs

    text = verbs.drive([f"{run}.toml"], "elcentro", str(folder / "again"),
                       with_=["pitch_flexibility"], target_peak=2.0).report()
    return stem, text, json.loads(Path(f"{stem}.json").read_text())


def test_the_amplification_says_where_the_cap_applies():
    _, text, result = drive()
    amp = result["drive"]["amplification"]
    cap = result["settings"]["cap"]
    # the largest is over the whole correction band (27 Hz here, 17x), beyond the cap: the
    # line says the cap applies near the fixed base only, and how it stands there
    assert amp["largest"] > cap and amp["window"] == pytest.approx(0.3)
    line = next(ln for ln in text.splitlines() if "amplification of the target" in ln)
    assert "the cap applies near the specimen's fixed-base frequencies only" in line
    assert amp["near_fixed_base"] <= cap and not amp["capped"] and amp["held"]
    assert f"within the cap {cap:g}" in line, line


def test_the_above_band_note_explains_the_default_band():
    *_, result = drive()
    note = next(n for n in result["notes"] if "above the table's 20 Hz band" in n)
    assert "by default 30 Hz" in note and "--band 20 keeps the drive within" in note
    assert result["settings"]["correction_band_hz"] == 30.0


def test_no_cell_of_the_drive_report_is_nan():
    _, text, result = drive()
    assert "nan" not in text.lower(), text
    elongation = next(ln for ln in text.splitlines() if ln.strip().startswith("time-scale"))
    assert elongation.split()[5] == "—", elongation  # its "at Hz": no spectrum, no frequency

    def finite(v) -> bool:
        if isinstance(v, dict):
            return all(finite(x) for x in v.values())
        if isinstance(v, list):
            return all(finite(x) for x in v)
        return not (isinstance(v, float) and math.isnan(v))

    assert finite(result)


def test_the_drive_run_declares_its_lead_and_reads_back(tmp_path):
    from vtable.errors import VtableError
    from vtable.runs import read_run
    from vtable.runs.format import command_from_dict

    stem, _, _ = drive()
    toml = tomllib.loads(Path(f"{stem}.toml").read_text())
    assert toml["command"] == {"lead_s": 1.0}
    run = read_run(f"{stem}.toml")
    assert run.drive().lead == 1.0
    with pytest.raises(VtableError, match=r"\[command\]\.lead_s: must be >= 0 s"):
        command_from_dict({"lead_s": -1.0}, "d.toml [command]")
