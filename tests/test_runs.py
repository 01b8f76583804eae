"""Runs: exact round trips, validation with one-line errors, property tests."""

from __future__ import annotations

import string
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from vtable import units
from vtable.errors import VtableError
from vtable.runs import campaign, read_hdf5, read_run, write_hdf5, write_run
from vtable.runs.model import FORMAT_UNITS, Run

TOML = '''format = "vtable-run/1"
title = "test"

[table]
preset = "eerc"

[specimen]
kind = "sdof"
weight_kip = 68.4
height_in = 219.0
frequency_hz = 2.87
damping = 0.01
'''


def write(tmp: Path, name: str, csv: str, toml: str = TOML) -> Path:
    (tmp / f"{name}.csv").write_text(csv)
    (tmp / f"{name}.toml").write_text(toml)
    return tmp / f"{name}.toml"


def _sample(tmp: Path) -> Run:
    t = 10.0 + np.arange(200) * 0.005
    rows = ["time,h_span,avg_hdisp,pitch_acc,my_gauge"]
    for i, ti in enumerate(t):
        rows.append(f"{float(ti)!r},{float(np.sin(ti))!r},{float(0.9 * np.sin(ti - 0.1))!r},"
                    f"{1e-3 * i!r},{i}")
    return read_run(write(tmp, "s", "\n".join(rows) + "\n",
                          TOML + '\n[units]\navg_hdisp = "mm"\nmy_gauge = "kip"\n'))


def test_read_converts_units_and_reports(tmp_path):
    r = _sample(tmp_path)
    assert r.time[0] == 10.0 and r.fs == pytest.approx(200.0)
    assert r.channel("h_span")[1] == pytest.approx(units.to_si(np.sin(10.005), "in"))
    assert r.channel("avg_hdisp")[1] == pytest.approx(0.9e-3 * np.sin(9.905))  # mm override
    assert r.units["my_gauge"] == "kip" and r.extra == ["my_gauge"]
    assert any("my_gauge" in m for m in r.reports)


def test_round_trips_are_identical(tmp_path):
    r = _sample(tmp_path)
    write_run(r, tmp_path / "copy")
    back = read_run(tmp_path / "copy.toml")
    assert back.meta == r.meta and back.units == r.units
    np.testing.assert_array_equal(back.time, r.time)
    for k in r.channels:
        np.testing.assert_array_equal(back.channels[k], r.channels[k])
    h5 = read_hdf5(write_hdf5(r, tmp_path / "r.h5"))
    assert h5.meta == r.meta and h5.units == r.units
    for k in r.channels:
        np.testing.assert_array_equal(h5.channels[k], r.channels[k])


CSV_OK = "time,h_span\n0,0\n0.005,1\n0.01,2\n"


@pytest.mark.parametrize("csv, toml, msg", [
    ("h_span,time\n0,0\n1,1\n", TOML, "first column must be 'time'"),
    ("time,h_span\n0,0\n0.005,1\n0.011,2\n", TOML, "column 'time' is not uniform"),
    ("time,h_span\n0,0\n,1\n0.01,2\n", TOML, "column 'time' has missing samples"),
    ("time,h_span,h_span\n0,0,0\n0.005,1,1\n", TOML, "duplicate column 'h_span'"),
    ("time,h_span\n0,0\n0.005,abc\n", TOML, "line 3, column 'h_span': 'abc' is not a number"),
    ("time,h_span\n0,0\n0.005\n", TOML, "line 3 has 1 fields, the header 2"),
    ("time,h_span\n0,0\n", TOML, "needs at least two samples"),
    ("", TOML, "empty file"),
    (CSV_OK, TOML.replace("vtable-run/1", "other/2"), "key 'format' must be 'vtable-run/1'"),
    (CSV_OK, TOML + '\n[units]\nh_span = "furlong"\n', "[units] h_span = 'furlong' is not a"),
    (CSV_OK, TOML.replace("weight_kip = 68.4", "weight_kip = -1.0"), "weight_kip must be > 0"),
    (CSV_OK, "format = [", "malformed TOML"),
])
def test_bad_runs_are_one_line_errors(tmp_path, csv, toml, msg):
    p = write(tmp_path, "bad", csv, toml)
    with pytest.raises(VtableError) as e:
        read_run(p)
    assert msg in str(e.value) and "\n" not in str(e.value)
    assert "bad.csv" in str(e.value) or "bad.toml" in str(e.value)


def test_unknown_key_and_channel_are_reported_and_kept(tmp_path):
    r = read_run(write(tmp_path, "u", "time,h_span,strain7\n0,0,1\n0.005,1,2\n",
                       'operator = "J. Doe"\n' + TOML))
    assert r.meta["operator"] == "J. Doe" and "strain7" in r.channels
    assert any("unknown key 'operator'" in m for m in r.reports)
    assert any("strain7" in m for m in r.reports)


def test_missing_samples_are_reported_not_filled(tmp_path):
    r = read_run(write(tmp_path, "m", "time,h_span,avg_hdisp\n0,0,0\n0.005,nan,1\n0.01,2,\n"
                                      "0.015,3,3\n"))
    assert r.missing == {"h_span": 1, "avg_hdisp": 1}
    assert np.isnan(r.channels["h_span"][1]) and np.isnan(r.channels["avg_hdisp"][2])
    assert any("'h_span' has 1 missing samples" in m for m in r.reports)
    with pytest.raises(VtableError, match="'avg_hdisp' has 1 missing samples; vtable does not"):
        r.channel("avg_hdisp")


def test_campaign_must_be_one_configuration(tmp_path):
    a = write(tmp_path, "a", CSV_OK)
    b = write(tmp_path, "b", CSV_OK, TOML.replace("frequency_hz = 2.87", "frequency_hz = 3.0"))
    c = write(tmp_path, "c", CSV_OK, TOML.replace('title = "test"', 'title = "other"'))
    assert len(campaign([a, c])) == 2
    with pytest.raises(VtableError, match=r"b: \[specimen\] differs from .*a's"):
        campaign([a, b])


# ---- property tests: malformed files never give a traceback or a silently wrong run ----
cells = st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                  st.text(alphabet=string.printable, max_size=6), st.just(""))
names = st.one_of(st.sampled_from(["time", *FORMAT_UNITS, "x", ""]),
                  st.text(alphabet=string.ascii_letters + "_,\"", max_size=8))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(header=st.lists(names, min_size=1, max_size=5),
       rows=st.lists(st.lists(cells, min_size=0, max_size=6), min_size=0, max_size=6))
def test_reader_never_crashes_on_malformed_csv(tmp_path, header, rows):
    text = ",".join(header) + "\n" + "\n".join(",".join(r) for r in rows) + "\n"
    p = write(tmp_path, "h", text)
    try:
        run = read_run(p)
    except VtableError as e:
        assert "\n" not in str(e) and ("h.csv" in str(e) or "h.toml" in str(e))
        return
    # accepted: then it is exactly what the file says
    assert run.time[0] == float(rows[0][0]) if rows and rows[0] else True
    assert np.all(np.diff(run.time) > 0)
    for h in run.channels:
        assert len(run.channels[h]) == len(run.time)
        assert np.isnan(run.channels[h]).sum() == run.missing.get(h, 0)


toml_values = st.one_of(st.integers(), st.floats(allow_nan=False), st.text(max_size=8),
                        st.booleans(), st.lists(st.integers(), max_size=3))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                   HealthCheck.function_scoped_fixture])
@given(key=st.sampled_from(["kind", "weight_kip", "height_in", "frequency_hz", "damping",
                            "bogus"]), value=toml_values, drop=st.booleans())
def test_reader_never_crashes_on_malformed_specimen(tmp_path, key, value, drop):
    import json

    lines = TOML.splitlines()
    lines = [ln for ln in lines if not ln.startswith(key + " ")]
    if not drop:
        v = json.dumps(value) if not isinstance(value, bool) else str(value).lower()
        lines.append(f"{key} = {v}")
    p = write(tmp_path, "k", CSV_OK, "\n".join(lines) + "\n")
    try:
        run = read_run(p)
    except VtableError as e:
        assert "\n" not in str(e) and "k.toml" in str(e)
        return
    spec = run.specimen()
    assert spec.weight > 0 and spec.frequency > 0 and spec.damping >= 0
