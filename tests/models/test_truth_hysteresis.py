"""The truth simulator's Bouc–Wen storeys (Wen 1976, Baber & Wen 1981, A = 1): a storey of
elastic stiffness k and drift u resists with α k u + (1 − α) k u_y z,
ż = (u̇ − β|u̇||z|ⁿ⁻¹z − γ u̇|z|ⁿ)/u_y; checked against the law itself (an elastic limit, the
strength bound, z integrated again here along the recorded drift, the storey shears from
the floor accelerations), for convergence, and in the run files it writes."""

from __future__ import annotations

import functools
import importlib
import tomllib

import numpy as np
import pytest
import truth
from truth import constants as const

HYBRID = truth.eerc_table(pitch="hybrid")
ELASTIC = truth.sdof(68.0, 219.0, 2.87, 0.01)  # Table 8.1
YIELD = {"yield_drift_in": 0.3, "post_yield_ratio": 0.1}
BUILDING = dict(weights_kip=[20.0, 20.0], heights_in=[80.0, 140.0],
                storey_k_kip_in=[60.0, 40.0], xi=0.02)
# storey 2 yields, with a shape where β ≠ γ and n ≠ 2 (a swap or a wrong power shows)
TOP_YIELDS = {"storeys": [2], "yield_drift_in": [0.15], "post_yield_ratio": [0.05],
              "n": 1.5, "beta": 0.7, "gamma": 0.3}


@functools.cache
def quake():
    return truth.earthquake_command("elcentro", peak_in=2.0)


@functools.cache
def run(spec, fs=256.0, table=HYBRID):
    return truth.simulate(table, spec, quake(), fs=fs)


def nrms(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2) / np.mean(b**2)))


def k_si(spec, storey=1):
    return spec.storey_k_kip_in[storey - 1] * const.KIP / const.INCH


# ---------------------------------------------------------------------------------------------
# the law


def test_alpha_one_is_the_elastic_frame_and_small_drift_nearly_so(monkeypatch):
    """α = 1 leaves only α k u = k u: the same response as the elastic frame (z is still
    integrated). Far below u_y, z ≈ u/u_y and the frame is nearly elastic too."""
    rigid = truth.sdof(68.0, 219.0, 2.87, 0.01,
                       hysteresis={"yield_drift_in": 0.3, "post_yield_ratio": 1.0})
    a, e = run(rigid), run(ELASTIC)
    for ch in ("avg_hdisp", "h1_force", "acc_n_ne", "pot_n_sw", "pitch_acc"):
        assert nrms(a.channels[ch], e.channels[ch]) < 1e-5, ch  # the elastic run's step: 2x
    # at the same internal step the two are the same run
    sim = importlib.import_module("truth.simulate")
    monkeypatch.setattr(sim, "DT_MAX", sim.DT_MAX_HYSTERESIS)
    e = truth.simulate(HYBRID, ELASTIC, quake())
    assert e.dt == a.dt
    for ch in ("avg_hdisp", "h1_force", "acc_n_ne", "pot_n_sw", "pitch_acc"):
        assert nrms(a.channels[ch], e.channels[ch]) < 1e-12, ch
    assert nrms(a.channels["floor1_drift"], e.internal["drift1"]) < 1e-12
    assert np.max(np.abs(a.internal["z1"])) > 0.9  # it went through yield, with no effect
    small = truth.random_command(10.0, (0, 10), peak_in=0.01, seed=3)
    soft = truth.sdof(68.0, 219.0, 2.87, 0.01,
                      hysteresis={"yield_drift_in": 0.3, "post_yield_ratio": 0.05})
    s, se = (truth.simulate(HYBRID, x, small) for x in (soft, ELASTIC))
    peak = np.max(np.abs(s.channels["floor1_drift"])) / const.INCH
    assert peak < 0.03  # a tenth of u_y
    off = nrms(s.channels["acc_n_ne"], se.channels["acc_n_ne"])
    print(f"drift peak {peak:.3g} in (u_y 0.3): acc_n_ne {off:.2g} off the elastic frame")
    assert off < 2e-3


def test_strength_bound_and_yield_under_a_strong_el_centro():
    """|V_h| ≤ α k |u| + (1 − α) k u_y z_max with z_max = (1/(β + γ))^(1/n); the storey
    shear from the floor acceleration is that plus the viscous c u̇ (exactly); the
    frame yields (peak drift > u_y) and dissipates energy."""
    spec = truth.sdof(68.0, 219.0, 2.87, 0.01, hysteresis=YIELD)
    res = run(spec)
    k, uy, alpha = k_si(spec), 0.3 * const.INCH, 0.1
    z_max = spec.hysteresis.z_max
    assert z_max == 1.0
    d, v, z = (res.internal[x] for x in ("drift1", "drift_vel1", "z1"))
    V = res.channels["floor1_shear"]
    c = res.built.Cs[0, 0]
    assert c == pytest.approx(2 * 0.01 * 2 * np.pi * 2.87 * 68.0 * const.KIP / const.G)
    # the storey shear (-m a) is the Bouc-Wen force plus the viscous one, to rounding
    law = alpha * k * d + (1 - alpha) * k * uy * z + c * v
    assert np.max(np.abs(V - law)) < 1e-9 * np.max(np.abs(V))
    assert np.array_equal(res.channels["floor1_drift"], d)
    bound = alpha * k * np.abs(d) + (1 - alpha) * k * uy * z_max * 1.02
    assert np.max(np.abs(V - c * v) / bound) < 1.0
    assert np.max(np.abs(z)) <= z_max * (1 + 1e-6)
    assert np.max(np.abs(d)) > 3 * uy  # 1.12 in
    # without viscous damping the measured shear itself keeps to the bound
    bare = run(truth.sdof(68.0, 219.0, 2.87, 0.0, hysteresis=YIELD))
    d0 = bare.channels["floor1_drift"]
    bound0 = alpha * k * np.abs(d0) + (1 - alpha) * k * uy * z_max * 1.02
    assert np.max(np.abs(bare.channels["floor1_shear"]) / bound0) < 1.0
    assert np.max(np.abs(d0)) > uy
    # energy: the hysteretic work less the recoverable (1-α) k u_y² z²/2 never decreases
    # (its rate is (1-α) k u_y |z|ⁿ⁺¹ (β|u̇| + γ u̇ sgn z) ≥ 0 for β ≥ |γ|)
    w = (1 - alpha) * k * uy
    work = np.concatenate([[0.0], np.cumsum(0.5 * (w * z[1:] * v[1:] + w * z[:-1] * v[:-1])
                                            * np.diff(res.t))])
    dissipated = (work - w * uy * z**2 / 2) / (0.5 * k * uy**2)
    assert dissipated[-1] > 30  # ≈ 62 elastic strain energies at yield
    assert np.min(np.diff(dissipated)) > -1e-3  # the trapezoid's own error only
    # the yielding frame draws less force from the actuators than the elastic one
    el = run(ELASTIC)
    assert np.max(np.abs(res.channels["h1_force"])) < 0.7 * np.max(np.abs(el.channels[
        "h1_force"]))


def bouc_wen_along(d, v, dt, uy, n, beta, gamma, nsub=16):
    """z integrated here again along a recorded drift: cubic Hermite between samples (drift
    and its rate), RK4 with `nsub` steps per sample."""
    def f(z, u):
        a = abs(z)
        return (u - beta * abs(u) * a ** (n - 1) * z - gamma * u * a**n) / uy

    def rate(i, s):
        return ((6 * s * s - 6 * s) * (d[i] - d[i + 1]) / dt + (3 * s * s - 4 * s + 1) * v[i]
                + (3 * s * s - 2 * s) * v[i + 1])

    z = np.zeros(len(d))
    zz, h = 0.0, dt / nsub
    for i in range(len(d) - 1):
        for q in range(nsub):
            s0, s1, sm = q / nsub, (q + 1) / nsub, (q + 0.5) / nsub
            k1 = f(zz, rate(i, s0))
            k2 = f(zz + 0.5 * h * k1, rate(i, sm))
            k3 = f(zz + 0.5 * h * k2, rate(i, sm))
            k4 = f(zz + h * k3, rate(i, s1))
            zz += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        z[i + 1] = zz
    return z


def test_building_storey_obeys_the_law_along_its_recorded_drift():
    spec = truth.building(**BUILDING, hysteresis=TOP_YIELDS)
    res = run(spec)
    it = res.internal
    assert "z2" in it and "z1" not in it
    uy = 0.15 * const.INCH
    z = bouc_wen_along(it["drift2"], it["drift_vel2"], 1 / res.fs, uy, 1.5, 0.7, 0.3)
    assert np.max(np.abs(z - it["z2"])) < 5e-5  # measured ≈ 1e-5
    assert np.max(np.abs(it["drift2"])) > 5 * uy  # 1.02 in: it yields, storey 1 stays 0.32
    # the shears from the floor accelerations are the storey forces: k₁ d₁ (elastic) and
    # α k₂ d₂ + (1-α) k₂ u_y z₂ (yielding), each plus the viscous forces of the floors above
    C = res.built.Cs
    udot = np.cumsum([it["drift_vel1"], it["drift_vel2"]], axis=0)  # u̇ of floors 1, 2
    visc = C @ udot
    k1, k2 = k_si(spec, 1), k_si(spec, 2)
    v1 = k1 * it["drift1"] + visc[0] + visc[1]
    v2 = 0.05 * k2 * it["drift2"] + 0.95 * k2 * uy * it["z2"] + visc[1]
    for V, ref in ((res.channels["floor1_shear"], v1), (res.channels["floor2_shear"], v2)):
        assert np.max(np.abs(V - ref)) < 1e-9 * np.max(np.abs(V))
    assert np.array_equal(res.channels["floor2_drift"], it["drift2"])
    # the storey shears: -Σ_{j≥K} m_j a_j from the floor accelerations
    m = np.array(spec.weights_kip) * const.KIP / const.G
    assert np.allclose(res.channels["floor2_shear"], -m[1] * res.channels["floor2_acc"],
                       rtol=0, atol=1e-9 * np.max(np.abs(v2)))
    assert np.allclose(res.channels["floor1_shear"],
                       -m[0] * res.channels["floor1_acc"] - m[1] * res.channels["floor2_acc"],
                       rtol=0, atol=1e-9 * np.max(np.abs(v1)))


def test_the_internal_step_is_converged(monkeypatch):
    """The 0.24 ms step (fs 256) against 0.12 ms: the drift and z agree to ~1e-6."""
    spec = truth.sdof(68.0, 219.0, 2.87, 0.01, hysteresis=YIELD)
    sim = importlib.import_module("truth.simulate")
    assert sim.stable_step(HYBRID, spec) == sim.DT_MAX_HYSTERESIS == 2.5e-4
    assert sim.stable_step(HYBRID, ELASTIC) == sim.DT_MAX == 5e-4
    a = run(spec)
    monkeypatch.setattr(sim, "DT_MAX_HYSTERESIS", 1.25e-4)
    b = truth.simulate(HYBRID, spec, quake(), fs=256.0)
    assert b.dt == pytest.approx(a.dt / 2)
    d, db = a.channels["floor1_drift"], b.channels["floor1_drift"]
    print(f"step {a.dt:.3g} s vs {b.dt:.3g} s: drift {np.max(np.abs(d - db)) / np.max(abs(db)):.2g}"
          f" of its peak, z {np.max(np.abs(a.internal['z1'] - b.internal['z1'])):.2g}")
    assert np.max(np.abs(d - db)) < 2e-6 * np.max(np.abs(db))
    assert np.max(np.abs(a.internal["z1"] - b.internal["z1"])) < 3e-6


# ---------------------------------------------------------------------------------------------
# declaring it


def test_declared_and_checked():
    spec = truth.building(**BUILDING, hysteresis={"yield_drift_in": 0.2,
                                                   "post_yield_ratio": [0.1, 0.05]})
    assert spec.declared()["hysteresis"] == {
        "storeys": [1, 2], "yield_drift_in": [0.2, 0.2], "post_yield_ratio": [0.1, 0.05],
        "n": 2.0, "beta": 0.5, "gamma": 0.5}
    assert "hysteresis" not in truth.building(**BUILDING).declared()
    assert truth.sdof(68.0, 219.0, 2.87, 0.01, hysteresis=YIELD).hysteresis.storeys == (1,)
    bad = [{"yield_drift_in": 0.2}, {"post_yield_ratio": 0.1},
           {**TOP_YIELDS, "storeys": [3]}, {**TOP_YIELDS, "storeys": [0]},
           {**TOP_YIELDS, "yield_drift_in": [0.1, 0.2]}, {**TOP_YIELDS, "yield_drift_in": -1},
           {**TOP_YIELDS, "post_yield_ratio": 1.5}, {**TOP_YIELDS, "n": 0.5},
           {**TOP_YIELDS, "beta": -0.5, "gamma": 0.2}, {**TOP_YIELDS, "alpha": 0.1},
           {**TOP_YIELDS, "storeys": [2, 2]}]
    for h in bad:
        with pytest.raises(truth.TruthError) as e:
            truth.building(**BUILDING, hysteresis=h)
        assert "\n" not in str(e.value) and "hysteresis" in str(e.value)
    with pytest.raises(truth.TruthError, match="storeys"):
        truth.sdof(68.0, 219.0, 2.87, 0.01, hysteresis={**YIELD, "storeys": [2]})
    with pytest.raises(truth.TruthError, match="yielding_storey"):
        truth.simulate(truth.eerc_table(effects={"yielding_storey": {"yield_fraction": 0.1}}),
                       truth.sdof(68.0, 219.0, 2.87, 0.01, hysteresis=YIELD), quake())


def test_perturb_moves_the_yield_drift_last():
    yielding = truth.building(**BUILDING, hysteresis={"yield_drift_in": [0.2, 0.3],
                                                      "post_yield_ratio": 0.05})
    elastic = truth.building(**BUILDING)
    for seed in range(12):
        d, de = truth.perturb(yielding, seed), truth.perturb(elastic, seed)
        assert d.storey_k_kip_in == de.storey_k_kip_in and d.xi == de.xi
        assert d.weights_kip == de.weights_kip and de.hysteresis is None
        f = np.array(d.hysteresis.yield_drift_in) / [0.2, 0.3]
        assert np.all((np.abs(f - 1) >= 0.05 - 1e-12) & (np.abs(f - 1) <= 0.1 + 1e-12))
        assert d.hysteresis.post_yield_ratio == (0.05, 0.05)
        assert (d.hysteresis.n, d.hysteresis.beta, d.hysteresis.gamma) == (2.0, 0.5, 0.5)
    f = np.array(truth.perturb(yielding, 3, yield_drift=0.3).hysteresis.yield_drift_in)
    assert np.all(np.abs(f / [0.2, 0.3] - 1) >= 0.15 - 1e-12)
    # an elastic specimen's declaration is what it was before hysteresis existed
    r = truth.building([20.0, 20.0, 20.0], [80.0, 140.0, 200.0],
                       frequencies_hz=[3.0, 8.5, 13.0], rayleigh=((3.0, 0.02), (13.0, 0.03)))
    assert truth.perturb(r, seed=3).storey_k_kip_in == pytest.approx(
        (88.33967921658231, 115.66484308914556, 106.18211222208724), rel=1e-12)


# ---------------------------------------------------------------------------------------------
# run files


def test_written_run_declares_hysteresis_and_has_drift_and_shear(tmp_path):
    from vtable.runs import read_run

    spec = truth.building(**BUILDING, hysteresis=TOP_YIELDS)
    res = run(spec)
    decl = truth.perturb(spec, seed=4)
    tpath, cpath = truth.write_run(tmp_path / "r", res, declared=decl, noise=0.0)
    text = tpath.read_text()
    assert "\n[specimen.hysteresis]\nstoreys = [2]\n" in text
    meta = tomllib.loads(text)
    h = meta["specimen"]["hysteresis"]
    assert h == decl.declared()["hysteresis"]
    assert h["yield_drift_in"] != pytest.approx([0.15], rel=0.04)  # the declared, not the truth
    assert (h["storeys"], h["post_yield_ratio"], h["n"], h["beta"], h["gamma"]) == (
        [2], [0.05], 1.5, 0.7, 0.3)
    header = cpath.read_text().splitlines()[0].split(",")
    assert header[-8:] == ["floor1_acc", "floor1_disp", "floor2_acc", "floor2_disp",
                           "floor1_drift", "floor1_shear", "floor2_drift", "floor2_shear"]
    data = np.loadtxt(cpath, delimiter=",", skiprows=1)
    col = {k: data[:, i] for i, k in enumerate(header)}
    for k, unit in (("floor1_drift", const.INCH), ("floor2_shear", const.KIP)):
        assert np.allclose(col[k], res.channels[k] / unit, rtol=1e-8,
                           atol=1e-8 * np.max(np.abs(res.channels[k] / unit)))
    rr = read_run(tpath)
    assert rr.units["floor1_drift"] == "in" and rr.units["floor1_shear"] == "kip"
    assert rr.meta["specimen"] == decl.declared()
    # noise as on the other response channels: its own per channel, x the channel's RMS
    noisy = truth.write_run(tmp_path / "n", res, declared=decl, noise=0.02, seed=7)[1]
    hn = noisy.read_text().splitlines()[0].split(",")
    dn = np.loadtxt(noisy, delimiter=",", skiprows=1)
    for k, unit in (("floor2_drift", const.INCH), ("floor1_shear", const.KIP)):
        clean = res.channels[k] / unit
        err = dn[:, hn.index(k)] - clean
        assert np.std(err) == pytest.approx(0.02 * np.sqrt(np.mean(clean**2)), rel=0.05)
    # LNEC runs are in SI and say so
    sdof = truth.sdof(2.0, 40.0, 4.0, 0.02, hysteresis={"yield_drift_in": 0.05,
                                                         "post_yield_ratio": 0.1})
    lnec = truth.simulate(truth.lnec_table(), sdof, truth.random_command(4.0, peak_in=0.5))
    lt = truth.write_run(tmp_path / "l", lnec, declared=sdof, noise=0.0)[0]
    units = tomllib.loads(lt.read_text())["units"]
    assert units["floor1_drift"] == "m" and units["floor1_shear"] == "N"


def test_campaign_runs_declare_it(tmp_path):
    spec = truth.sdof(68.0, 219.0, 2.87, 0.01, hysteresis=YIELD)
    paths = truth.campaign(tmp_path, HYBRID, spec, truth.perturb(spec, seed=2),
                           duration_s=4.0, quake_peak_in=1.0)
    for p in paths:
        meta = tomllib.loads(p.read_text())
        assert meta["specimen"]["hysteresis"]["post_yield_ratio"] == [0.1]
        assert meta["specimen"]["hysteresis"]["yield_drift_in"] != [0.3]
        assert p.with_suffix(".csv").read_text().splitlines()[0].endswith(
            ",floor1_drift,floor1_shear")


def test_elastic_runs_keep_their_columns(tmp_path):
    b = truth.building(**BUILDING)
    res = truth.simulate(HYBRID, b, truth.random_command(2.0, peak_in=0.1, seed=1))
    assert not any(k.endswith(("_drift", "_shear")) for k in res.channels)
    assert not any(k.startswith("z") for k in res.internal)
    tpath, cpath = truth.write_run(tmp_path / "e", res, declared=truth.perturb(b, 1))
    assert cpath.read_text().splitlines()[0] == (
        "time,h_span,avg_hdisp,h1_disp,h2_disp,h3_disp,h_vel,avg_hacc,h1_force,h2_force,"
        "h3_force,pitch_acc,pitch_disp,acc_n_ne,acc_n_nw,pot_n_sw,pot_n_se,floor1_acc,"
        "floor1_disp,floor2_acc,floor2_disp")
    assert "hysteresis" not in tomllib.loads(tpath.read_text())["specimen"]
    s = truth.simulate(HYBRID, ELASTIC, truth.random_command(2.0, peak_in=0.1, seed=1))
    sc = truth.write_run(tmp_path / "s", s, declared=ELASTIC)[1]
    assert sc.read_text().splitlines()[0] == (
        "time,h_span,avg_hdisp,h1_disp,h2_disp,h3_disp,h_vel,avg_hacc,h1_force,h2_force,"
        "h3_force,pitch_acc,pitch_disp,acc_n_ne,acc_n_nw,pot_n_sw,pot_n_se")
