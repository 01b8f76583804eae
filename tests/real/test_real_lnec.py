"""Issue 18's real-data acceptance on LNEC's measured pink-noise run (../shared/data/real):
what `identify` can quote of the loop, and why the time-domain diagnosis cannot end near
the noise floor. Each fact read from the data alone (numpy and scipy, a few lines) is the
independent reference for what vtable reads of it: its sensor check, its notch check, its
noise floor and its black box (issue 34: a test of the data alone cannot fail on vtable).
Skipped when the data are not beside the repository.

Measured on this run (H1, 2048-point frames unless said; numbers in the asserts):

- Declared as shipped (a bare table under LNEC's P control, the `lnec-st1d` preset),
  eq 6.15 with the valve lag fits x_t/x_c only roughly (R² 0.966) and would quote k_o 16.7
  1/s, 17 % under the design's 20.18 1/s (K_q x 129.93 V/m / A): the record holds a notch
  near 3.2 Hz (|x_t/x_c| 0.39, a specimen holding the platen) and a rise to 1.24 at 2 Hz
  that a P-controlled bare table cannot make, and the bare loop bends k_o to absorb them.
  `identify` finds that resonance itself (its "resonator" structure, eq 7.9 with the
  valve lag and the mass ratio free, wins by AIC) and quotes the loop with it held: k_o
  20.5 1/s (1.5 % from the design), f_s 3.04 Hz, ξ_s 0.12, about 840 kg.
- Declared with the specimen nobody documented, a SDOF (eq 7.9, the valve lag held): the
  fit's R² over the specimen mass is highest (0.994) for 0.9-1.0 t, where k_o is 19.6-19.9
  1/s (within 3 % of the design) and f_s 3.22-3.25 Hz, ξ_s 0.075-0.082. The mass is read
  from the data (the R² profile), not chosen to hit k_o.
- The two table channels disagree with each other whatever the model: the measured
  acceleration differs from the second derivative of the measured displacement by 41 %
  (5-10 Hz) and 90 % (10-20 Hz) of the acceleration, at coherence 0.98 between them
  (a systematic transducer or platen-to-actuator dynamic, not noise); a model of one rigid
  platen seen by both channels cannot come within a few noise floors of both.
- No time-invariant model driven by h_span can end within 3x the noise floor (5.3 %):
  even the non-parametric H1 leaves 8.0 % of the displacement (79 % of it at 2-5 Hz) and
  16.8 % of the acceleration (82 % at 5-20 Hz) incoherent with the drive.
- The specimen softens during the run: the notch of x_t/x_c moves from 3.22 Hz (first
  32 s) to 2.93 Hz (last 32 s), which no time-invariant model follows.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import real_data
import scipy.signal as sg

from vtable.diagnose import noise_floor
from vtable.diagnose.limits import black_box
from vtable.diagnose.sensors import sensor_check
from vtable.diagnose.stationarity import stationarity_check
from vtable.ident.report import identify_run
from vtable.runs import read_run

K_O_DESIGN = 1.9345e-3 * 129.93 / 0.012456  # 1/s: K_q x displacement gain / A = 20.18
KG_PER_KIP = 4448.2216 / 9.80665


pytestmark = real_data.NEEDED


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    """A copy of the run (TOML + decompressed CSV) in a temporary folder."""
    return real_data.copy_run(tmp_path_factory.mktemp("real_lnec")).parent


def _with_specimen(run_dir: Path, name: str, specimen: str) -> Path:
    """The run with its [specimen] replaced (the CSV shared by a symlink)."""
    text = (run_dir / "lnec_pink_2.toml").read_text()
    new = re.sub(r"\[specimen\]\n(?:[^\[\n].*\n|\n)*", specimen + "\n", text, count=1)
    assert new != text
    (run_dir / f"{name}.toml").write_text(new)
    csv = run_dir / f"{name}.csv"
    if not csv.exists():
        csv.symlink_to(run_dir / "lnec_pink_2.csv")
    return run_dir / f"{name}.toml"


def _sdof(run_dir: Path, weight_kip: float) -> dict:
    path = _with_specimen(run_dir, f"sdof_{weight_kip:g}", (
        f'[specimen]\nkind = "sdof"\nweight_kip = {weight_kip}\nheight_in = 40.0\n'
        'frequency_hz = 3.2\ndamping = 0.08\n'))
    return identify_run(read_run(path)).to_json()["table_sdof"]


def test_as_declared_identify_finds_the_undeclared_resonance(run_dir):
    d = identify_run(read_run(run_dir / "lnec_pink_2.toml")).to_json()
    ls = d["loop_structure"]
    assert ls["best"] == "resonator", ls["why"]
    bare = ls["candidates"]["eq_6_15_lag"]
    assert 15.8 < bare["params"]["k_o"] < 17.6, bare["params"]  # 16.7 ± 0.44: bent
    assert 0.95 < bare["r2"] < 0.98, bare["r2"]  # 0.966: the loop holds what it has not
    ol = d["open_loop"]
    p = ol["params"]
    assert abs(p["k_o"] / K_O_DESIGN - 1) < 0.05, p  # 20.5 ± 0.41 1/s vs 20.18
    assert 2.9 < p["f_s"] < 3.3 and 0.05 < p["xi_s"] < 0.2, p  # 3.04 Hz, 0.12
    assert 600 < p["u"] * 1975.1 < 1200, p  # about 840 kg (the eq 7.9 scan: 0.9-1.0 t)
    assert ol["r2"] > bare["r2"] + 0.015  # 0.988
    assert "does not declare" in ol["note_resonator"]


def test_with_the_undocumented_specimen_k_o_is_the_designs(run_dir):
    weights = (1.4, 2.0, 2.2, 2.9)  # kip: 635, 907, 998, 1315 kg
    fits = {w: _sdof(run_dir, w) for w in weights}
    r2 = {w: f["r2"] for w, f in fits.items()}
    best = max(r2, key=r2.get)
    # the data choose the mass: R² 0.987 at 635 kg, 0.994 at 0.9-1.0 t, 0.991 at 1.3 t
    assert best in (2.0, 2.2), r2
    assert r2[best] > 0.99 and r2[best] - r2[1.4] > 0.005 and r2[best] - r2[2.9] > 0.002, r2
    p = fits[best]["params"]
    assert abs(p["k_o"] / K_O_DESIGN - 1) < 0.05, p  # 19.6-19.9 1/s vs 20.18
    assert 3.1 < p["f_s"] < 3.35 and 0.05 < p["xi_s"] < 0.12, p
    assert not fits[best]["flags"], fits[best]["flags"]
    assert 0.8e3 < best * KG_PER_KIP < 1.1e3


def _channels(run_dir: Path) -> dict[str, np.ndarray]:
    a = np.genfromtxt(run_dir / "lnec_pink_2.csv", delimiter=",", names=True)
    return {k: np.asarray(a[k], dtype=float) for k in a.dtype.names}


def test_the_two_table_channels_disagree_beyond_any_rigid_platen(run_dir):
    d = _channels(run_dir)
    fs = 1 / (d["time"][1] - d["time"][0])
    x = d["avg_hdisp"] * 1e-3
    a = d["avg_hacc"] * 9.80665
    f = np.fft.rfftfreq(len(x), 1 / fs)
    X, A = np.fft.rfft(x - x.mean()), np.fft.rfft(a - a.mean())

    def mismatch(lo: float, hi: float) -> float:
        b = (f >= lo) & (f < hi)
        return float(np.sqrt(np.sum(abs(A[b] + (2 * np.pi * f[b]) ** 2 * X[b]) ** 2)
                             / np.sum(abs(A[b]) ** 2)))

    assert mismatch(2, 5) < 0.25  # 19 %: where the channels roughly agree
    assert mismatch(5, 10) > 0.33  # 41 %
    assert mismatch(10, 20) > 0.75  # 90 %
    fc, coh = sg.coherence(x, a, fs=fs, nperseg=2048)
    band = (fc > 5) & (fc < 12)
    # systematic: the channels are coherent where they differ (median 0.977, least 0.87)
    assert np.median(coh[band]) > 0.95 and coh[band].min() > 0.8
    # vtable's sensor check reads the same: |ẍ/s²x|, here |H1 of a over x|/ω² on 1024-point
    # frames, the median over each band's coherent lines (1.21 and 1.67)
    check = sensor_check(read_run(run_dir / "lnec_pink_2.toml"))
    assert check is not None and not check.agree, check
    ratio = {b: m for b, m, _, _ in check.bands}
    fh, sxa = sg.csd(x, a, fs=fs, nperseg=1024)
    _, sxx = sg.welch(x, fs=fs, nperseg=1024)
    _, cxa = sg.coherence(x, a, fs=fs, nperseg=1024)
    for lo, hi in ((5, 10), (10, 20)):
        b = (fh >= lo) & (fh < hi) & (cxa > 0.5)
        mine = float(np.median(abs(sxa[b] / sxx[b]) / (2 * np.pi * fh[b]) ** 2))
        assert ratio[f"{lo}-{hi} Hz"] == pytest.approx(mine, rel=0.06), (ratio, lo, mine)


def test_the_specimen_softens_during_the_run(run_dir):
    d = _channels(run_dir)
    fs = 1 / (d["time"][1] - d["time"][0])
    xc, xt = d["h_span"], d["avg_hdisp"]
    w = int(32 * fs)

    def notch(s0: int) -> float:
        f, gxy = sg.csd(xc[s0:s0 + w], xt[s0:s0 + w], fs=fs, nperseg=2048)
        _, gxx = sg.welch(xc[s0:s0 + w], fs=fs, nperseg=2048)
        m = (f > 2.3) & (f < 4.5)
        return float(f[m][np.argmin(abs(gxy / gxx)[m])])

    first, last = notch(0), notch(len(xc) - w)
    assert 3.15 < first < 3.3, first  # 3.22 Hz
    assert last < first - 0.15, (first, last)  # 2.93 Hz: at least 1.5 lines lower
    # vtable's check (the first and last thirds, 55 s each) sees the notch move down too
    check = stationarity_check(read_run(run_dir / "lnec_pink_2.toml"))
    assert check is not None and check.notch is not None, check
    f1, f2, window = check.notch
    third = len(xc) // 3
    assert window == pytest.approx(third / fs)
    assert f1 == pytest.approx(notch_over(xc[:third], xt[:third], fs), abs=0.1), f1
    assert f2 == pytest.approx(notch_over(xc[-third:], xt[-third:], fs), abs=0.1), f2
    assert f2 < f1 - 0.1, (f1, f2)  # 3.21 -> 3.05 Hz


def notch_over(xc: np.ndarray, xt: np.ndarray, fs: float) -> float:
    """The least |H1| of x_t over x_c at 2.3-4.5 Hz (2048-point frames)."""
    f, gxy = sg.csd(xc, xt, fs=fs, nperseg=2048)
    _, gxx = sg.welch(xc, fs=fs, nperseg=2048)
    m = (f > 2.3) & (f < 4.5)
    return float(f[m][np.argmin(abs(gxy / gxx)[m])])


def test_no_time_invariant_model_of_the_drive_reaches_three_noise_floors(run_dir):
    """What any linear time-invariant model driven by h_span must leave: the incoherent
    part (1 - γ²) of each channel's power (H1 on 4096-point frames, the best such model
    there is). vtable's noise floor of the run (`noise_floor`, 1.78 %: what `vtable
    diagnose` prints) is well below it: a floor that swallowed the incoherent part would
    call the run explained."""
    d = _channels(run_dir)
    fs = 1 / (d["time"][1] - d["time"][0])
    floor = noise_floor([read_run(run_dir / "lnec_pink_2.toml")])
    assert floor == pytest.approx(0.0178, abs=0.002), floor
    floor3 = 3 * floor
    for ch, least, band, share in (("avg_hdisp", 0.065, (2, 5), 0.6),  # 8.0 %, 79 %
                                   ("avg_hacc", 0.14, (5, 20), 0.7)):  # 16.8 %, 82 %
        y = d[ch]
        f, pyy = sg.welch(y, fs=fs, nperseg=4096)
        _, coh = sg.coherence(d["h_span"], y, fs=fs, nperseg=4096)
        u = (1 - coh) * pyy
        lti = np.sqrt(u[f > 0].sum() / pyy[f > 0].sum())
        assert lti > least > floor3, (ch, lti)
        in_band = u[(f >= band[0]) & (f < band[1])].sum() / u[f > 0].sum()
        assert in_band > share, (ch, in_band)


def _h1_prediction(x_fit, y_fit, x, fs, nperseg=2048):
    """The H1 of y over x estimated on the fit segment (lines where the drive has no
    power set to 0), as an impulse response (centred, tapered), applied to x."""
    _, s_xy = sg.csd(x_fit, y_fit, fs, nperseg=nperseg)
    _, s_xx = sg.welch(x_fit, fs, nperseg=nperseg)
    h1 = np.where(s_xx > 1e-6 * s_xx.max(), s_xy / np.maximum(s_xx, 1e-300), 0)
    h = np.roll(np.fft.irfft(h1, nperseg), nperseg // 2) * sg.windows.tukey(nperseg, 0.2)
    return sg.fftconvolve(x, h)[nperseg // 2:nperseg // 2 + len(x)]


def test_the_table_changes_between_the_diagnosis_training_and_held_out_segments(run_dir):
    """The diagnosis trains on the run's first 30 s and scores its last 40 %. Even the
    non-parametric time-invariant model (H1 from the drive) fitted on those first 30 s
    predicts the held-out table displacement at 16 % and acceleration at 38 %; fitted on
    the 30 s just before the held-out segment, at 5.3 % and 25 %: the run changes (the
    specimen's notch moves, test_stationarity), and no time-invariant model trained on its
    start reaches three noise floors (5.3 %) on its end."""
    d = _channels(run_dir)
    fs = 1 / (d["time"][1] - d["time"][0])
    x = d["h_span"]
    held = int(0.6 * len(x))
    n30 = int(30 * fs)
    err = {}
    for ch in ("avg_hdisp", "avg_hacc"):
        y = d[ch]
        for name, fit in (("first", slice(0, n30)), ("adjacent", slice(held - n30, held))):
            p = _h1_prediction(x[fit], y[fit], x[held:], fs)
            err[ch, name] = np.linalg.norm(y[held:] - p) / np.linalg.norm(y[held:])
    assert err["avg_hdisp", "first"] > 0.12 and err["avg_hacc", "first"] > 0.3, err
    # vtable's black box (limits.black_box, on the same 2048-point frames) on the same
    # segments agrees with this one
    run = read_run(run_dir / "lnec_pink_2.toml")
    xs = run.channel("h_span")
    for ch in ("avg_hdisp", "avg_hacc"):
        for name, fit in (("first", slice(0, n30)), ("adjacent", slice(held - n30, held))):
            box = black_box(xs, run.channel(ch), fit, slice(held, len(xs)), frames=(2048,))
            assert box is not None
            assert box[0] == pytest.approx(err[ch, name], rel=0.1), (ch, name, box[0], err)
    assert err["avg_hdisp", "adjacent"] < 0.5 * err["avg_hdisp", "first"], err
    assert err["avg_hacc", "adjacent"] < 0.8 * err["avg_hacc", "first"], err
    assert (err["avg_hdisp", "first"] + err["avg_hacc", "first"]) / 2 > 3 * 3 * 0.0178


def test_the_run_written_in_si_reads_the_same(run_dir):
    """A metric lab's spelling of the same run: its columns converted here with numpy (mm
    -> m, g -> m/s², 1 g = 9.80665 m/s²), `[units]` in `m` and `m/s^2`, and the specimen
    declared in SI both ways: every channel reads as the original's, to the digits written."""
    text = (run_dir / "lnec_pink_2.toml").read_text()
    head = (run_dir / "lnec_pink_2.csv").read_text().split("\n", 1)[0]
    data = np.loadtxt(run_dir / "lnec_pink_2.csv", delimiter=",", skiprows=1)
    units_of = dict(re.findall(r'^(\w+) = "(mm|g)"$', text, re.M))
    cols = head.split(",")
    for j, c in enumerate(cols):
        data[:, j] *= {"mm": 1e-3, "g": 9.80665}.get(units_of.get(c), 1.0)
    si = re.sub(r'= "mm"$', '= "m"', text, flags=re.M)
    si = re.sub(r'= "g"$', '= "m/s^2"', si, flags=re.M)
    np.savetxt(run_dir / "lnec_si.csv", data, delimiter=",", header=head, comments="",
               fmt="%.17g")
    (run_dir / "lnec_si.toml").write_text(si)
    a, b = read_run(run_dir / "lnec_pink_2.toml"), read_run(run_dir / "lnec_si.toml")
    assert set(b.units.values()) == {"m", "m/s2"} and b.channels.keys() == a.channels.keys()
    for c in a.channels:
        np.testing.assert_allclose(b.channels[c], a.channels[c], rtol=1e-14, atol=1e-18)
    for spec in ('[specimen]\nkind = "sdof"\nweight_kip = 2.0\nheight_in = 40.0\n'
                 'frequency_hz = 3.2\ndamping = 0.08\n',
                 '[specimen]\nkind = "sdof"\nmass_kg = 907.18474\nheight_m = 1.016\n'
                 'frequency_hz = 3.2\ndamping = 0.08\n'):
        name = "kip" if "weight_kip" in spec else "kg"
        s = read_run(_with_specimen(run_dir, f"spec_{name}", spec)).declared.specimen
        assert s.mass == pytest.approx(907.18474, rel=1e-9) and s.height == \
            pytest.approx(1.016, rel=1e-12)


def test_a_drive_for_the_bare_table_drives_its_own_motion(run_dir, tmp_path):
    """LNEC's table carries no declared specimen: the effective motion x_t + θh has no
    height, said in one line with what to do, and `--objective table` drives x_t (the
    height was asked for, and refused, whatever the objective)."""
    from conftest import run_cli

    toml = str(run_dir / "lnec_pink_2.toml")
    args = ["drive", toml, "--target", "elcentro", "--target-peak", "20mm", "--with",
            "sensor_offset", "--out", str(tmp_path / "drv")]
    code, _, err = run_cli(args)
    assert code == 2 and "has no effective height" in err and "--objective table" in err
    code, out, err = run_cli([*args, "--objective", "table", "--json"])
    assert code == 0, err
    res = json.loads(out)
    assert res["objective"] == "table" and res["effective_height_m"] == 0.0
    # on the model, the drive reproduces x_t far better than the target played as it is
    assert res["drive"]["nrms"] < 0.25 * res["baselines"]["target as it is"]["nrms"]
    assert (tmp_path / "drv.csv").is_file() and (tmp_path / "drv.toml").is_file()
