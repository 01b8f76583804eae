"""Identification on another lab's table (issue 11): the LNEC uniaxial table from the
truth simulator, its command given only as a drive file offset by 37 lost samples
(drive_offset_s = "auto"), a type-0 plant from an independent generator, and bad drive
descriptions through the CLI.

Record lengths: the random run is 60 s of pink 0-40 Hz noise at 200 Hz (2048-point frames,
10 averages, Δf 0.098 Hz: the loop at f_o 24 Hz, ξ_o 0.17 is resolved and the band reaches
1.5 f_o = 36 Hz); the earthquake (El Centro, time-scaled, 26 s) carries too little
above 10 Hz to tell the loop structures apart, so its lag is fitted with the table's
described loop held.
"""

from __future__ import annotations

import functools
import json
import re
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
import scipy.signal as sg

sys.path.insert(0, str(Path(__file__).parents[1]))
import truth

from vtable.cli import main
from vtable.ident.drive import align
from vtable.ident.report import identify_run
from vtable.ident.result import Identification
from vtable.runs import read_run
from vtable.runs.lab import lab_table
from vtable.runs.table import table_from_dict
from vtable.tables.lab import bare_loop

FS = 200.0
LOST = 37  # samples the acquisition lost: the drive leads by 37/200 s
NONE = truth.none()


@functools.cache
def lnec_campaign() -> dict:
    """The LNEC campaign, made once: (truth result, RUN.toml path) per run."""
    folder = Path(tempfile.mkdtemp(prefix="lnec_ident_"))
    table = truth.lnec_table()
    cmds = {"random": truth.random_command(60.0, (0.0, 40.0), rms_in=0.1, seed=3, pink=True),
            "earthquake": truth.earthquake_command("elcentro", peak_in=1.0, seed=2)}
    out = {}
    for k, (name, cmd) in enumerate(cmds.items()):
        res = truth.simulate(table, NONE, cmd, fs=FS)
        paths = truth.write_run(folder / name, res, declared=NONE, noise=0.01, seed=3 + k,
                                drive={"unit": "mm", "scale": 2.0, "offset_samples": LOST,
                                       "offset": "auto"})
        out[name] = (res, paths[0])
    return out


def _cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _lag(reports: list[str]) -> tuple[int, float, float]:
    """(rounded, estimate, σ) in samples from the reader's drive line."""
    line = next(r for r in reports if "from the drive file" in r)
    m = re.search(r"estimated lag (\d+) samples \(([\d.]+) s\): ([\d.]+) ± ([\d.e-]+) samples",
                  line)
    assert m, line
    assert float(m.group(2)) == pytest.approx(int(m.group(1)) / FS, abs=1e-4)
    return int(m.group(1)), float(m.group(3)), float(m.group(4))


def test_lnec_drive_auto_offset_to_one_sample():
    for name, (res, path) in lnec_campaign().items():
        read = read_run(path)
        assert not read.has("h_span")  # the reader leaves "auto" to the alignment
        run = align(read)
        n, est, sd = _lag(run.reports)
        assert n == LOST and abs(est - LOST) < 1.0, (name, est)
        assert sd < 0.5, (name, sd)
        # the command made from the drive: the truth's x_c at the acquisition's samples
        x_c = res.channels["h_span"][LOST:]
        assert np.max(np.abs(run.channels["h_span"] - x_c)) < 1e-6 * np.max(np.abs(x_c))
        assert "drive file" in next(r for r in run.reports if "from the drive file" in r)


def test_lnec_identify_recovers_eq_6_16_and_the_valve_lag(capsys, tmp_path):
    (_, path), (_, quake) = lnec_campaign()["random"], lnec_campaign()["earthquake"]
    code, out, err = _cli(capsys, "identify", str(path), str(quake), "--json",
                          str(tmp_path / "id.json"))
    assert code == 0, err
    d = json.loads((tmp_path / "id.json").read_text())["runs"]
    ref = bare_loop(lab_table(table_from_dict({"preset": "lnec-st1d"}, "preset")))
    o = d[0]["open_loop"]
    assert o["model"] == "eq 6.15 with a first-order valve lag" and o["flags"] == []
    p = o["params"]
    assert p["f_o"] == pytest.approx(ref.f_o, rel=0.03)    # 24.15 Hz
    assert p["xi_o"] == pytest.approx(ref.xi_o, rel=0.03)  # 0.170
    assert p["k_o"] == pytest.approx(ref.k_o, rel=0.03)    # 20.05 1/s
    assert p["tau"] == pytest.approx(0.0246, rel=0.05)
    ls = d[0]["loop_structure"]
    assert ls["fits_eq_6_15"] and ls["best"] == "eq_6_15_lag"
    assert ls["dc_gain"] == pytest.approx(1.0, abs=0.01)
    # the table is the run's: LNEC's platen, one actuator, no pitch sections
    for r in d:
        assert r["table"]["platen_mass_kg"] == pytest.approx(1975.1)
        assert r["table"]["horizontal_actuators"] == 1
        for sec in ("rocking impedance", "hysteresis"):
            assert "lnec-st1d table does not pitch" in r["skipped"][sec]
    assert d[0]["horizontal_spring"]["mass_kg"] == pytest.approx(1975.1)
    assert "estimated lag 37 samples (0.185 s)" in out
    assert "τ 0.02" in out and "skipped rocking impedance: the lnec-st1d table" in out


def _type0_run(folder: Path, gain: float = 0.8, f_n: float = 8.0, zeta: float = 0.4) -> Path:
    """An electrodynamic shaker under P control, written here (not by vtable, not by the
    truth): x_t/x_c = K ω_n²/(s² + 2ζω_n s + ω_n²), 0.1-40 Hz random, 60 s at 200 Hz,
    1 % noise on x_t."""
    rng = np.random.default_rng(11)
    t = np.arange(int(60 * FS)) / FS
    sos = sg.butter(4, [0.1, 40.0], btype="band", fs=FS, output="sos")
    x_c = sg.sosfilt(sos, rng.standard_normal(len(t)))
    x_c *= 0.01 / np.max(np.abs(x_c))
    w = 2 * np.pi * f_n
    x_t = sg.lsim(sg.TransferFunction([gain * w * w], [1, 2 * zeta * w, w * w]), x_c, t)[1]
    x_t += 0.01 * np.std(x_t) * rng.standard_normal(len(t))
    stem = folder / "shaker"
    rows = "".join(f"{float(a)!r},{float(b)!r},{float(c)!r}\n"
                   for a, b, c in zip(t, x_c, x_t, strict=True))
    stem.with_suffix(".csv").write_text("time,h_span,avg_hdisp\n" + rows)
    stem.with_suffix(".toml").write_text(
        'format = "vtable-run/1"\n[table]\npreset = "lnec-st1d"\n[specimen]\nkind = "none"\n'
        '[units]\nh_span = "m"\navg_hdisp = "m"\n')
    return stem.with_suffix(".toml")


def test_a_type_0_plant_is_not_forced_into_eq_6_15(capsys, tmp_path):
    d = identify_run(read_run(_type0_run(tmp_path))).to_json()
    assert "open_loop" not in d and "horizontal_spring" not in d
    why = d["skipped"]["servo loop fit"]
    assert "does not fit eq 6.15" in why and "DC gain is 0.8" in why
    assert "a type-0 second-order loop fits" in why
    ls = d["loop_structure"]
    assert not ls["fits_eq_6_15"] and ls["best"] == "type_0"
    assert ls["dc_gain"] == pytest.approx(0.8, abs=0.02)
    p = ls["candidates"]["type_0"]["params"]
    assert p["gain"] == pytest.approx(0.8, rel=0.02)
    assert p["f_n"] == pytest.approx(8.0, rel=0.02)
    assert p["zeta"] == pytest.approx(0.4, rel=0.05)
    print(Identification.from_json(d).report())
    out = capsys.readouterr().out
    assert "open loop (" not in out and "⚠ x_t/x_c does not fit eq 6.15" in out
    assert "parameters not quoted" in out
    pattern = r"a type-0 second-order loop: gain 0\.(79|80)\d* ± [\d.e-]+, f_n 7\.9"
    assert re.search(pattern, out), out


def _drive_run(folder: Path, **command) -> Path:
    """A small LNEC run without h_span, its [command] from `command`."""
    t = np.arange(400) / FS
    x = 1e-3 * np.sin(2 * np.pi * 2.0 * t)
    (folder / "drive.csv").write_text("time,displacement\n" + "".join(
        f"{float(a)!r},{float(1e3 * b)!r}\n" for a, b in zip(t, x, strict=True)))
    (folder / "run.csv").write_text("time,avg_hdisp\n" + "".join(
        f"{float(a)!r},{float(b)!r}\n" for a, b in zip(t, x, strict=True)))
    cmd = {"drive_file": "drive.csv", "drive_unit": "mm", **command}
    lines = "\n".join(f"{k} = {json.dumps(v)}" for k, v in cmd.items())
    (folder / "run.toml").write_text(
        'format = "vtable-run/1"\n[table]\npreset = "lnec-st1d"\n[specimen]\nkind = "none"\n'
        f'[units]\navg_hdisp = "m"\n[command]\n{lines}\n')
    return folder / "run.toml"


@pytest.mark.parametrize(("command", "key", "what"), [
    ({"drive_file": "nowhere.csv"}, "drive_file", "is not a file"),
    ({"drive_unit": "kg"}, "drive_unit", "is a displacement"),
    ({"drive_scale": 0.0}, "drive_scale", "must be > 0"),
    ({"drive_scale": -2.0}, "drive_scale", "must be > 0"),
    ({"drive_offset_s": 30.0}, "drive_offset_s", "outside the run"),
    ({"drive_offset_s": "soon"}, "drive_offset_s", "expected a number"),
])
def test_bad_drive_descriptions_are_one_line(capsys, tmp_path, command, key, what):
    path = _drive_run(tmp_path, **command)
    code, _out, err = _cli(capsys, "identify", str(path))
    assert code == 2
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert "run.toml" in err and f"[command].{key}" in err and what in err, err


def test_bad_drive_file_contents_are_one_line(capsys, tmp_path):
    path = _drive_run(tmp_path, drive_offset_s=0.0)
    (tmp_path / "drive.csv").write_text("time,displacement\n0.0,1.0\n0.005,x\n")
    code, _out, err = _cli(capsys, "identify", str(path))
    assert code == 2 and err.count("\n") == 1
    assert "drive.csv: line 3" in err and "drive_file" in err, err


def test_given_offset_and_a_column_that_wins(tmp_path):
    path = _drive_run(tmp_path, drive_offset_s=0.0)
    run = read_run(path)
    assert np.allclose(run.channels["h_span"], run.channels["avg_hdisp"], atol=1e-12)
    line = next(r for r in run.reports if "drive file" in r)
    assert "drive.csv (mm, scale 1), offset 0 s (0 samples, given)" in line
    # an h_span column and a drive file: the column is the command, the drive is checked
    csv = (tmp_path / "run.csv").read_text().splitlines()
    rows = [csv[0] + ",h_span"] + [f"{ln},{2 * float(ln.split(',')[1])!r}" for ln in csv[1:]]
    (tmp_path / "run.csv").write_text("\n".join(rows) + "\n")
    text = (tmp_path / "run.toml").read_text().replace('avg_hdisp = "m"',
                                                       'avg_hdisp = "m"\nh_span = "m"')
    (tmp_path / "run.toml").write_text(text)
    run = read_run(path)
    line = next(r for r in run.reports if "drive file" in r)
    assert "the h_span column is the command" in line and "scale 2" in line
    assert "⚠ they disagree" in line
    assert np.allclose(run.channels["h_span"], 2 * run.channels["avg_hdisp"])
