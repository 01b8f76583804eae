import numpy as np
import pytest
import scipy.integrate

from vtable import units
from vtable.errors import VtableError
from vtable.signals import (
    band_limited_random,
    bandpass_trapezoid,
    differentiate,
    el_centro,
    integrate_to_displacement,
    process_record,
    pulse,
    read_at2,
    read_at2_folder,
    sine,
)


def test_random_is_reproducible_and_band_limited():
    t, a = band_limited_random(16.0, 0.005, (0.0, 25.0), peak=0.1, seed=7)
    _, b = band_limited_random(16.0, 0.005, (0.0, 25.0), peak=0.1, seed=7)
    _, c = band_limited_random(16.0, 0.005, (0.0, 25.0), peak=0.1, seed=8)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    assert np.max(np.abs(a)) == pytest.approx(0.1)
    f = np.fft.rfftfreq(len(t), 0.005)
    P = np.abs(np.fft.rfft(a)) ** 2
    assert P[f > 25.5].sum() < 1e-20 * P.sum()
    _, d = band_limited_random(11.0, 0.005, (0.0, 32.0), rms=2.0, seed=1)
    assert np.sqrt(np.mean(d**2)) == pytest.approx(2.0)


def test_random_rejects_band_above_nyquist():
    with pytest.raises(VtableError, match="Nyquist 50"):
        band_limited_random(10, 0.01, (0, 60))


def test_sine_and_pulse():
    t, x = sine(2.0, 0.001, 5.0, 0.5)
    assert x[t == 0.05][0] == pytest.approx(0.5)
    t, p = pulse(3.0, 0.001, width=1.0, amplitude=0.02, start=0.5)
    assert p.max() == pytest.approx(0.02) and t[np.argmax(p)] == pytest.approx(1.0)
    assert p[0] == 0 and p[-1] == 0


def test_el_centro_record():
    r = el_centro()
    assert len(r.acc) == 3995 and r.dt == pytest.approx(0.01)
    assert r.pga / units.G == pytest.approx(0.313, abs=0.001)
    pgv = np.max(np.abs(scipy.integrate.cumulative_trapezoid(r.acc, dx=r.dt)))
    assert pgv * 100 == pytest.approx(29.7, abs=0.2)  # cm/s, shared/data/README.md


def test_section_9_2_processing():
    cmd = process_record(el_centro(), length_scale=3.2801)
    assert cmd.dt == pytest.approx(0.01 / 1.811, rel=1e-3)  # time scale √3.2801 = 1.811
    d = cmd.displacement
    assert np.max(np.abs(d)) == pytest.approx(units.to_si(4.0, "in"))
    v = np.gradient(d, cmd.dt)
    assert abs(d[0]) < 1e-12 and abs(d[-1]) < 1e-12
    # one-sided difference at the ends: within half a step of acceleration
    assert abs(v[0]) < 2e-3 * np.abs(v).max() and abs(v[-1]) < 2e-3 * np.abs(v).max()
    # acceleration back by differentiation: integrating it twice returns the displacement
    back = integrate_to_displacement(cmd.acceleration, cmd.dt)
    assert np.max(np.abs(back - d)) < 0.01 * np.max(np.abs(d))
    # the forward scheme (first order, its value at i centred on i+1) agrees with the
    # central one (§9.2: "results of both schemes were very similar")
    fwd = differentiate(d, cmd.dt, "forward")
    assert np.corrcoef(fwd[10:-12], cmd.acceleration[11:-11])[0, 1] > 0.995


def test_integration_of_a_known_signal():
    dt = 0.001
    t = np.arange(0, 2 + dt / 2, dt)
    x = np.sin(np.pi * t) ** 2 * np.sin(6 * np.pi * t)  # zero end displacement & velocity
    a = np.gradient(np.gradient(x, dt, edge_order=2), dt, edge_order=2)
    np.testing.assert_allclose(integrate_to_displacement(a, dt), x, atol=5e-4)


def test_bandpass_removes_out_of_band():
    dt = 0.005
    t = np.arange(0, 20, dt)
    x = np.sin(2 * np.pi * 0.1 * t) + np.sin(2 * np.pi * 5 * t) + np.sin(2 * np.pi * 40 * t)
    y = bandpass_trapezoid(x, dt, (0.5, 0.55, 23, 24))
    mid = slice(1000, 3000)
    np.testing.assert_allclose(y[mid], np.sin(2 * np.pi * 5 * t[mid]), atol=0.05)


AT2 = """PEER NGA STRONG MOTION DATABASE RECORD
IMPERIAL VALLEY 5/19/40, EL CENTRO ARRAY #9, 180
ACCELERATION TIME SERIES IN UNITS OF G
NPTS=   17, DT=   .0100 SEC
  .0010000  .0020000 -.0030000  .0040000  .0050000
 -.0060000  .0070000 -.0080000  .0090000  .0100000
  .0110000 -.1200000  .0130000  .0140000  .0150000
  .0160000  .0170000
"""


def test_at2_reader(tmp_path):
    p = tmp_path / "ELC180.AT2"
    p.write_text(AT2)
    r = read_at2(p)
    assert r.dt == 0.01 and len(r.acc) == 17 and r.notes == ()
    assert r.acc[2] == pytest.approx(-0.003 * units.G)
    assert "EL CENTRO" in r.name
    (tmp_path / "B.AT2").write_text(AT2)
    assert len(read_at2_folder(tmp_path)) == 2


@pytest.mark.parametrize("text, msg", [
    (AT2.replace("NPTS=   17", "NPTS=   18"), "header says NPTS=18 but the file has 17 values"),
    (AT2.replace("NPTS=   17, DT=   .0100 SEC", "nothing here"), "line 4 must give NPTS= and DT="),
    (AT2.replace(".0050000", "abc"), "line 5: non-numeric acceleration value: 'abc' is not a"),
    (AT2.replace(".0050000", "1_0"), "'1_0' is not a number"),
    ("short\n", "too short"),
    ("\n".join(AT2.splitlines()[:5]).replace("NPTS=   17", "NPTS=    5") + "\n",
     "5 samples; a record needs at least 16"),
    (AT2.replace(".0050000", "1e300"), r"sample 5: 1e\+300 g is not a plausible acceleration"),
    (AT2.replace("DT=   .0100", "DT=   100.0"), "time step 100 s is not an accelerogram's"),
])
def test_at2_errors(tmp_path, text, msg):
    p = tmp_path / "bad.AT2"
    p.write_text(text)
    with pytest.raises(VtableError, match=msg):
        read_at2(p)


def _csv_record(tmp_path, header, acc, dt=0.01, digits=None):
    t = np.arange(len(acc)) * dt
    fmt = (lambda x: f"{x:.{digits}g}") if digits else repr
    p = tmp_path / "rec.csv"
    p.write_text(header + "\n" + "".join(f"{fmt(float(a))},{float(b)!r}\n"
                                          for a, b in zip(t, acc, strict=True)))
    return p


def test_csv_record_header_states_the_unit(tmp_path):
    from vtable.signals import read_csv_record

    acc = el_centro().acc[:400] / units.G  # in g
    g = read_csv_record(_csv_record(tmp_path, "time_s,accel_g", acc))
    assert g.pga == pytest.approx(np.max(np.abs(acc)) * units.G) and g.notes == ()
    gal = read_csv_record(_csv_record(tmp_path, "time_s, accel_cm_s2", acc * 980.665))
    np.testing.assert_allclose(gal.acc, g.acc, rtol=1e-12)
    ms2 = read_csv_record(_csv_record(tmp_path, "time_s,accel_m_s2", acc * units.G))
    np.testing.assert_allclose(ms2.acc, g.acc, rtol=1e-12)
    # a time column printed with 4 significant digits (steps within 1e-3 of the median)
    four = read_csv_record(_csv_record(tmp_path, "time_s,accel_g", acc, digits=4))
    assert four.dt == pytest.approx(0.01, rel=1e-9)


@pytest.mark.parametrize("header", ["time,accel_g", "time_s,accel", "time_s,accel_in_s2",
                                    "time_s;accel_g", "time_s,accel_g,extra"])
def test_csv_record_unknown_header_is_an_error(tmp_path, header):
    from vtable.signals import read_csv_record

    p = _csv_record(tmp_path, header, np.zeros(20))
    with pytest.raises(VtableError, match=r"header .*expected time_s and one of accel_g, "
                                          r"accel_cm_s2, accel_m_s2") as e:
        read_csv_record(p)
    assert "\n" not in str(e.value) and "rec.csv" in str(e.value)


@pytest.mark.parametrize("rows, msg", [
    ("0,0.1\n0.01,0.2\n", "2 samples; a record needs at least 16"),   # vtable assess crashed
    ("".join(f"{0.01 * i!r},0.1\n" for i in range(20)).replace("0.05,", "0.07,"),
     "time stamps must increase"),
    ("".join(f"{0.01 * i!r},0.1\n" for i in range(20)).replace("0.1\n", "nan\n", 1),
     "'nan' is not a number"),
    ("".join(f"{0.01 * i!r},0.1\n" for i in range(20)).replace("0.1\n", "0.1,3\n", 1),
     "has 3 fields; expected 2"),
])
def test_bad_csv_records_are_one_line_errors(tmp_path, rows, msg):
    from vtable.signals import read_csv_record

    p = tmp_path / "bad.csv"
    p.write_text("time_s,accel_g\n" + rows)
    with pytest.raises(VtableError, match=msg) as e:
        read_csv_record(p)
    assert "\n" not in str(e.value) and "bad.csv" in str(e.value)


def test_implausible_record_unit_is_warned_with_the_likely_unit(tmp_path):
    from vtable.signals import read_csv_record

    # El Centro in cm/s² (PGA 0.313 g = 307 gal) written under a g header
    acc_gal = el_centro().acc[:1000] / units.G * 980.665
    r = read_csv_record(_csv_record(tmp_path, "time_s,accel_g", acc_gal))
    assert len(r.notes) == 2
    assert "PGA 307 g is implausible for g; is the record in cm/s² (gal)?" in r.notes[0]
    assert "PGV" in r.notes[1] and "implausible" in r.notes[1]
    # the same numbers in g under a cm/s² header: 0.3 gal, implausibly small
    r = read_csv_record(_csv_record(tmp_path, "time_s,accel_cm_s2", acc_gal / 980.665))
    assert r.notes == (f"{tmp_path / 'rec.csv'}: PGA 0.313 cm/s2 is implausibly small for "
                       "cm/s² (gal); is the record in g?",)
    # AT2 files are in g: one in m/s² has PGA 3 "g" (plausible) - no note; in cm/s², a note
    at2 = tmp_path / "GAL.AT2"
    vals = " ".join(f"{v:.6f}" for v in acc_gal[:400])
    at2.write_text(f"PEER\nEL CENTRO\nUNITS OF G\nNPTS= 400, DT= .0100 SEC\n{vals}\n")
    assert "is the record in cm/s² (gal)?" in read_at2(at2).notes[0]


def test_a_cut_earthquake_shakes_as_the_whole_record_does():
    """`--duration` on an earthquake takes the processed record's first seconds scaled as
    the whole record is (issue 33: the cut used to be scaled to --peak itself, and the same
    --peak gave half the shaking): El Centro at 2 in, its first 5 and 15 s, against the
    whole command over the same seconds."""
    from vtable.signals import make_command

    full = make_command("earthquake", record="elcentro", peak_in=2.0)

    def acc(c):
        return np.gradient(np.gradient(c.x, c.t), c.t)

    for seconds in (5.0, 15.0):
        cut = make_command("earthquake", record="elcentro", peak_in=2.0, duration=seconds)
        n = len(cut.t)
        a_full, a_cut = acc(full)[:n], acc(cut)
        # the same shaking: 1.03 g peak in both, 2.0-2.1 % NRMS apart, all of it in the last
        # 2 s (1.7 s of the 5) that bring the cut to rest, at most 0.014 g there
        # (tests/unit/test_simulate_edges.py holds the cut to the whole before them)
        assert np.abs(a_cut).max() == pytest.approx(np.abs(a_full).max(), rel=0.01)
        assert np.linalg.norm(a_cut - a_full) / np.linalg.norm(a_full) < 0.03
        assert cut.table["peak_in"] == pytest.approx(2.0)  # the whole record's peak
        assert "scaled as the whole record is" in cut.notes[-1], cut.notes
