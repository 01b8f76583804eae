"""What `vtable identify` computes for a run: Table 3.1, springs from frequencies,
rocking impedance, hysteresis, and the servo-loop fits (report units in the output)."""

from __future__ import annotations

from typing import Any

import numpy as np

from vtable import units
from vtable.analytic import closed_forms
from vtable.errors import VtableError
from vtable.ident.fits import Fit, fit_open_loop, fit_table_sdof
from vtable.ident.structure import (
    hysteresis,
    pitch_moment,
    rocking_impedance,
    rocking_springs,
    table_3_1,
)
from vtable.ident.tf import transfer_function
from vtable.params.loops import OpenLoop
from vtable.params.specimen import NoSpecimen, RigidBlock, SDOFSpecimen
from vtable.runs.model import Run


def _fit_dict(fit: Fit) -> dict[str, Any]:
    return {"params": fit.params, "stderr": fit.stderr, "r2": fit.r2, "nrmse": fit.nrmse,
            "method": fit.method, "n_points": fit.n_points}


def _has(run: Run, *names: str) -> bool:
    return all(run.has(n) and not run.missing.get(n) for n in names)


def identify_run(run: Run, table_weight_kip: float = 100.0) -> dict[str, Any]:
    """Everything identifiable from the run's channels; sections whose channels are absent
    are listed under `skipped` with the reason."""
    out: dict[str, Any] = {"run": run.name, "fs_hz": run.fs, "duration_s": run.duration,
                           "reports": list(run.reports), "skipped": {}}
    spec = run.specimen() if "specimen" in run.meta else NoSpecimen()
    m_t = units.weight_to_mass(table_weight_kip)
    # servo loop: x_t/x_c (eq 6.15 bare; eq 7.9 with a SDOF structure)
    if _has(run, "h_span", "avg_hdisp"):
        tf = transfer_function(run.channel("h_span"), run.channel("avg_hdisp"), run.fs,
                               min(2048, 2 ** int(np.log2(len(run.time) / 4))))
        try:
            if isinstance(spec, NoSpecimen | RigidBlock):
                fit = fit_open_loop(tf.f, tf.H, tf.coherence, band=(0.2, 25.0))
                ol = OpenLoop(f_o=fit["f_o"], xi_o=fit["xi_o"], k_o=fit["k_o"])
                out["open_loop"] = _fit_dict(fit)
                out["open_loop"]["gain_margin"] = closed_forms.gain_margin_bare(ol)
                mass = m_t + (spec.mass if isinstance(spec, RigidBlock) else 0.0)
                f = np.array([2.0, 5.0, 10.0])
                k_h, c_h = closed_forms.feedback_spring(mass, ol, f)  # eqs 5.15-5.16
                out["horizontal_spring"] = {
                    "f_hz": f.tolist(), "k_h_kip_per_in": units.from_si(k_h, "kip/in").tolist(),
                    "c_h_lb_s_per_in": units.from_si(c_h, "lb-s/in").tolist()}
            elif isinstance(spec, SDOFSpecimen):
                fit = fit_table_sdof(tf.f, tf.H, spec.mass / m_t, tf.coherence, band=(0.2, 25.0))
                out["table_sdof"] = _fit_dict(fit)
        except VtableError as e:
            out["skipped"]["servo loop fit"] = str(e)
    else:
        out["skipped"]["servo loop fit"] = "needs h_span and avg_hdisp"
    # structure: Table 3.1, springs from frequencies
    if isinstance(spec, SDOFSpecimen) and _has(run, "avg_hacc", "pitch_acc", "h_span") and (
            _has(run, "acc_n_ne") or _has(run, "acc_n_nw")):
        t = table_3_1(run)
        out["table_3_1"] = [{"case": n, "f_hz": f, "damping": x} for n, f, x in t.rows()]
        out["table_3_1_methods"] = {
            e.name: {"primary": _fit_dict(e.primary), "appendix_d": _fit_dict(e.amplitude),
                     "circle": _fit_dict(e.circle) if e.circle else None}
            for e in (t.fixed, t.rocking, t.coupled)}
        try:
            k_r = closed_forms.rocking_stiffness_from_frequencies(t.fixed.f, t.rocking.f,
                                                                 spec.mass, spec.height)
            k_h = closed_forms.horizontal_stiffness_from_frequencies(
                t.fixed.f, t.coupled.f, spec.mass, spec.height, k_r)
            out["springs_from_frequencies"] = {
                "k_r_lb_in_per_rad": units.from_si(k_r, "lb-in/rad"),
                "k_h_kip_per_in": units.from_si(k_h, "kip/in"), "equations": "5.4, 5.5"}
        except VtableError as e:
            out["skipped"]["springs from frequencies"] = str(e)
        f_c = t.coupled.f
    else:
        out["skipped"]["table 3.1"] = ("needs a sdof specimen and avg_hacc, pitch_acc, h_span "
                                       "and acc_n_ne or acc_n_nw")
        f_c = None
    # rocking impedance and hysteresis from the vertical actuators and stabilizers
    forces = [f"v{i}_force" for i in range(1, 5)] + [f"p{i}_stab" for i in range(1, 5)]
    if _has(run, *forces) and (_has(run, "pitch_disp") or _has(run, "pitch_acc")):
        G = {g: rocking_impedance(run, groups=grp) for g, grp in
             (("total", ("vertical", "stabilizer")), ("vertical actuators", ("vertical",)),
              ("stabilizers", ("stabilizer",)))}
        if f_c is None:  # where the table pitches most, below 20 Hz
            th = transfer_function(run.channel("h_span") if _has(run, "h_span") else
                                   pitch_moment(run), run.channel("pitch_acc"), run.fs,
                                   G["total"].f.size * 2 - 2)
            band = (th.f > 0.5) & (th.f < 20.0)
            f_c = float(th.f[band][np.argmax(np.abs(th.H[band]) / th.f[band] ** 2)])
        f_eval = f_c
        out["rocking_impedance"] = {"f_hz": f_eval, **{
            g: dict(zip(("k_r_lb_in_per_rad", "c_r_lb_in_s_per_rad"),
                        (units.from_si(k, "lb-in/rad"), units.from_si(c, "lb-in-s/rad")),
                        strict=True))
            for g, (k, c) in ((g, rocking_springs(tf, f_eval)) for g, tf in G.items())}}
        if _has(run, "pitch_disp"):
            h = hysteresis(run.channel("pitch_disp"), pitch_moment(run), run.dt, f_eval)
            out["hysteresis"] = {"k_r_lb_in_per_rad": units.from_si(h.stiffness, "lb-in/rad"),
                                 "c_r_lb_in_s_per_rad": units.from_si(h.damping_coefficient,
                                                                      "lb-in-s/rad"),
                                 "damping_ratio": h.damping_ratio, "equations": "5.12-5.13"}
    else:
        out["skipped"]["rocking impedance"] = "needs v1..v4_force, p1..p4_stab and pitch"
    return out


def print_identification(d: dict[str, Any]) -> None:
    print(f"{d['run']}: {d['duration_s']:.1f} s at {d['fs_hz']:.0f} Hz")
    for r in d["reports"]:
        print(f"  note: {r}")
    if "open_loop" in d:
        p = d["open_loop"]["params"]
        e = d["open_loop"]["stderr"]
        print(f"  open loop (eq 6.15): f_o {p['f_o']:.3f} ± {e['f_o']:.3f} Hz, ξ_o "
              f"{p['xi_o']:.3f} ± {e['xi_o']:.3f}, k_o {p['k_o']:.2f} ± {e['k_o']:.2f} 1/s "
              f"(R² {d['open_loop']['r2']:.4f}); gain margin {d['open_loop']['gain_margin']:.2f}")
    if "table_sdof" in d:
        p = d["table_sdof"]["params"]
        print(f"  table + SDOF (eq 7.9): f_o {p['f_o']:.2f} Hz, ξ_o {p['xi_o']:.3f}, k_o "
              f"{p['k_o']:.2f}, f_s {p['f_s']:.3f} Hz, ξ_s {p['xi_s']:.4f} "
              f"(R² {d['table_sdof']['r2']:.4f})")
    if "table_3_1" in d:
        print(f"  {'Table 3.1':<28} {'f (Hz)':>8} {'damping (%)':>12}")
        for row in d["table_3_1"]:
            print(f"  {row['case']:<28} {row['f_hz']:8.3f} {100 * row['damping']:12.2f}")
    if "springs_from_frequencies" in d:
        s = d["springs_from_frequencies"]
        print(f"  springs (eqs 5.4, 5.5): k_r {s['k_r_lb_in_per_rad']:.3g} lb-in/rad, "
              f"k_h {s['k_h_kip_per_in']:.3g} kip/in")
    if "rocking_impedance" in d:
        g = d["rocking_impedance"]
        print(f"  rocking impedance G_r = M/θ at {g['f_hz']:.3f} Hz (eqs 5.9-5.11):")
        for k in ("total", "vertical actuators", "stabilizers"):
            print(f"    {k:<20} k_r {g[k]['k_r_lb_in_per_rad']:.3g} lb-in/rad, c_r "
                  f"{g[k]['c_r_lb_in_s_per_rad']:.3g} lb-in-s/rad")
    if "hysteresis" in d:
        h = d["hysteresis"]
        print(f"  hysteresis (eqs 5.12-5.13): k_r {h['k_r_lb_in_per_rad']:.3g} lb-in/rad, "
              f"ξ_v {100 * h['damping_ratio']:.2f} %")
    for k, why in d["skipped"].items():
        print(f"  skipped {k}: {why}")
