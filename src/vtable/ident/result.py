"""The identification of one run as a typed result: `Identification`, with its JSON
(`to_json`, the `vtable identify --json` record) and its printed text (`report`), each
number with its validity flags (⚠, vtable.ident.validity)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from vtable import display, units
from vtable.ident.loop import STRUCTURES
from vtable.ident.validity import Flag, marker


@dataclass
class Identification:
    """What `vtable.ident.report.identify_run` found in one run (report units; each
    section a JSON-ready dict, None when it was not made: `skipped` says why).

    Sections: the run's `table`; the servo loop (`loop_structure`, the eq 6.15 fit
    `open_loop` and the eqs 5.15-5.16 `horizontal_spring`, or the eq 7.9 `table_sdof`);
    Table 3.1 (`table_3_1` rows, `table_3_1_methods`) and the eqs 5.4-5.5
    `springs_from_frequencies`; the eqs 5.9-5.11 `rocking_impedance` and the eqs
    5.12-5.13 `hysteresis`."""

    run: str
    fs_hz: float
    duration_s: float
    reports: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)
    table: dict[str, Any] | None = None
    loop_structure: dict[str, Any] | None = None
    open_loop: dict[str, Any] | None = None
    horizontal_spring: dict[str, Any] | None = None
    table_sdof: dict[str, Any] | None = None
    table_3_1: list[dict[str, Any]] | None = None
    table_3_1_methods: dict[str, Any] | None = None
    springs_from_frequencies: dict[str, Any] | None = None
    rocking_impedance: dict[str, Any] | None = None
    hysteresis: dict[str, Any] | None = None
    display: str = field(default="imperial", metadata={"text only": True})  # `vtable.display`

    def to_json(self) -> dict[str, Any]:
        """The JSON record (the sections made, in this order; `display`, the units the
        text shows, is not in it)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if getattr(self, f.name) is not None and not f.metadata.get("text only")}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Identification:
        """The result back from its JSON record."""
        return cls(**d)

    def report(self) -> str:
        """The printed identification (`identification_text`)."""
        return identification_text(self.to_json(), self.display)


def _warn_lines(out: list[str], flags: list[dict[str, Any]], indent: str = "      ") -> None:
    seen = set()
    for f in flags:
        if f["text"] not in seen:
            seen.add(f["text"])
            out.append(f"{indent}⚠ {f['text']}")


def _mark(flags: list[dict[str, Any]], param: str) -> str:
    return marker([Flag(f["code"], f["text"], f["param"], f["source"]) for f in flags], param)


def _frame(d: dict[str, Any]) -> str:
    a, r = d.get("averages"), d.get("resolution_hz")
    return "" if a is None else f", {int(a)} averages, Δf {r:.3g} Hz"


def _v(x: float | None, fmt: str, scale: float = 1.0, width: int = 0) -> str:
    """A number for the printed tables, "—" when there is none (NaN, None)."""
    if x is None or not np.isfinite(x):
        return f"{'—':>{width}}"
    return f"{scale * x:{width}{fmt}}"


def _methods(out: list[str], m: dict[str, Any]) -> None:
    """The comparison methods of one Table 3.1 row, each with its flag markers."""
    parts = []
    for key, label in (("appendix_d", "appendix D"), ("circle", "circle fit")):
        fit = m.get(key)
        if fit is None or fit is m.get("primary") or (
                m.get("primary") and fit["method"] == m["primary"]["method"]):
            continue
        p, fl = fit["params"], fit["flags"]
        xi = p["xi_n"]
        if xi is None or not np.isfinite(xi):  # a reason, not "— % ⚠ no value"
            why = next((f["text"] for f in fl if f["param"] == "xi_n"), "no finite value")
            xi_text = f"damping not identified ({why})"
        else:
            xi_text = f"{_v(xi, '.2f', 100)} %{_mark(fl, 'xi_n')}"
        parts.append(f"{label} {_v(p['f_n'], '.3f')} Hz{_mark(fl, 'f_n')} {xi_text}")
    for label, why in m.get("skipped", {}).items():
        parts.append(f"{label} skipped ({why})")
    if parts:
        out.append("      compare: " + "; ".join(parts))


def _structure(out: list[str], ls: dict[str, Any]) -> None:
    """The loop-structure verdict; when the loop is not eq 6.15, the structure that fits
    with its parameters (the eq 6.15 ones are not quoted)."""
    mark = "" if ls["fits_eq_6_15"] else "⚠ "
    out.append(f"  loop structure: {mark}{ls['why']}")
    for n in ls.get("notes", []):
        out.append(f"      note: {n}")
    for key, c in ls["candidates"].items():
        if ls["fits_eq_6_15"] and key != ls["best"]:
            continue
        if not ls["fits_eq_6_15"] and c.get("type1", STRUCTURES.get(key) and
                                            STRUCTURES[key].type1):
            out.append(f"      {c['name']}: ΔAIC {c['delta_aic']:+.0f} (R² {c['r2']:.4f}), "
                       "parameters not quoted")
            continue
        ps = ", ".join(f"{k} {v:.4g} ± {c['stderr'][k]:.2g}" for k, v in c["params"].items())
        out.append(f"      {c['name']}: {ps} (ΔAIC {c['delta_aic']:+.0f}, R² {c['r2']:.4f})")


def _in(values, report_unit: str, fam: str, spec: str = ".3g") -> tuple[str, str]:
    """Values given in `report_unit` (the JSON's) as the text shows them (`vtable.display`:
    the report's units, or metric for a metric run): the numbers joined and the unit."""
    si = [units.to_si(v, report_unit) for v in np.atleast_1d(values)]
    unit = display.unit_for(report_unit, fam)
    return ", ".join(f"{display.from_si(v, unit):{spec}}" for v in si), display.label(unit)


def identification_text(d: dict[str, Any], fam: str = "imperial") -> str:
    """The identification of one run (`Identification.to_json()`) as printed text, each
    number with its flags (⚠); its stiffnesses and dampings in the units of `fam`."""
    out: list[str] = []
    out.append(f"{d['run']}: {d['duration_s']:.1f} s at {d['fs_hz']:.0f} Hz")
    for r in d["reports"]:
        out.append(f"  note: {r}")
    for r in d.get("notes", []):
        out.append(f"  note: {r}")
    if "table" in d:
        t = d["table"]
        out.append(f"  table: {t['name']} (DOFs {', '.join(t['dofs'])}; platen "
                   f"{t['platen_mass_kg']:.6g} kg, {t['horizontal_actuators']} horizontal "
                   f"actuator(s), valve time constant {t['valve_time_constant_s']:g} s)")
    if "loop_structure" in d:
        _structure(out, d["loop_structure"])
    if "open_loop" in d:
        o = d["open_loop"]
        p, e, fl = o["params"], o["stderr"], o["flags"]
        gm = "" if not o["gain_margin_flags"] else " ⚠ from a flagged fit"
        lag = (f", τ {p['tau']:.4f} ± {e['tau']:.2g} s{_mark(fl, 'tau')}" if "tau" in p
               else "")
        out.append(f"  open loop ({o.get('model', 'eq 6.15')}): f_o {p['f_o']:.3f} ± "
                   f"{e['f_o']:.3g} Hz{_mark(fl, 'f_o')}, ξ_o {p['xi_o']:.3f} ± {e['xi_o']:.3g}"
                   f"{_mark(fl, 'xi_o')}, k_o {p['k_o']:.2f} ± {e['k_o']:.3g} 1/s{_mark(fl, 'k_o')}"
                   f"{lag} (R² {o['r2']:.4f}{_frame(o)}); gain margin (eq 6.20) "
                   f"{o['gain_margin']:.2f}{gm}")
        _warn_lines(out, fl)
        if "note_resonator" in o:
            out.append(f"      note: {o['note_resonator']}")
        hs = d.get("horizontal_spring")
        if hs:
            ks, ku = _in(hs["k_h_kip_per_in"], "kip/in", fam)
            cs, cu = _in(hs["c_h_lb_s_per_in"], "lb-s/in", fam)
            fs = ", ".join(f"{f:g}" for f in hs["f_hz"])
            out.append(f"  horizontal spring (eqs 5.15-5.16) at {fs} Hz: k_h {ks} {ku}, c_h {cs} "
                       f"{cu}" + (" ⚠ from a flagged fit" if hs["flags"] else ""))
    if "table_sdof" in d:
        o = d["table_sdof"]
        p, fl = o["params"], o["flags"]
        out.append(f"  table + SDOF (eq 7.9): f_o {p['f_o']:.2f} Hz{_mark(fl, 'f_o')}, ξ_o "
                   f"{p['xi_o']:.3f}{_mark(fl, 'xi_o')}, k_o {p['k_o']:.2f}{_mark(fl, 'k_o')}, "
                   f"f_s {p['f_s']:.3f} Hz{_mark(fl, 'f_s')}, ξ_s {p['xi_s']:.4f}"
                   f"{_mark(fl, 'xi_s')} (R² {o['r2']:.4f}{_frame(o)})")
        _warn_lines(out, fl)
        if fl:
            out.append(f"      frames: {o['frame']}")
        for key in ("note_controller", "note"):
            if o.get(key):
                out.append(f"      note: {o[key]}")
    if d.get("table_3_1"):
        out.append(f"  {'Table 3.1':<28} {'f (Hz)':>8} {'damping (%)':>12}   frames")
        for row in d["table_3_1"]:
            fl = row["flags"]
            out.append(f"  {row['case']:<28} {_v(row['f_hz'], '.3f', width=8)}{_mark(fl, 'f_n')} "
                       f"{_v(row['damping'], '.2f', 100, 12)}{_mark(fl, 'xi_n')}   "
                       f"{row['nperseg']} pts, {row['averages']} avg, "
                       f"Δf {row['resolution_hz']:.3g} Hz")
            _warn_lines(out, fl)
            if fl:
                out.append(f"      frames: {row['frame']}")
            _methods(out, d.get("table_3_1_methods", {}).get(row["case"], {}))
    if "springs_from_frequencies" in d:
        s = d["springs_from_frequencies"]
        fl, e = s["flags"], s["stderr"]
        kr, kru = _in(s["k_r_lb_in_per_rad"], "lb-in/rad", fam)
        kh, khu = _in(s["k_h_kip_per_in"], "kip/in", fam)
        ekr, ekh = (_in(e[k], u, fam, ".2g")[0] for k, u in (("k_r_lb_in_per_rad", "lb-in/rad"),
                                                             ("k_h_kip_per_in", "kip/in")))
        out.append(f"  springs (eqs 5.4, 5.5): k_r {kr} ± {ekr}{_mark(fl, 'k_r')} {kru}, k_h "
                   f"{kh} ± {ekh}{_mark(fl, 'k_h')} {khu}"
                   + (" ⚠ from flagged frequencies" if any(f["source"] for f in fl) else ""))
        _warn_lines(out, s["flags"])
    if "rocking_impedance" in d:
        g = d["rocking_impedance"]
        out.append(f"  rocking impedance G_r = M/θ at {g['f_hz']:.3f} Hz, {g['at']} "
                   f"(eqs 5.9-5.11, θ from {g['theta_from']}):")
        for k in ("total", "vertical actuators", "stabilizers"):
            if k not in g:
                out.append(f"    {k:<20} skipped: {g['skipped'][k]}")
                continue
            fl = g[k]["flags"]
            kr, kru = _in(g[k]["k_r_lb_in_per_rad"], "lb-in/rad", fam)
            cr, cru = _in(g[k]["c_r_lb_in_s_per_rad"], "lb-in-s/rad", fam)
            out.append(f"    {k:<20} k_r {kr}{_mark(fl, 'k_r')} {kru}, c_r {cr}"
                       f"{_mark(fl, 'c_r')} {cru} "
                       f"(γ² {g[k]['coherence']:.3f}, {int(g[k]['averages'])} avg)")
            _warn_lines(out, fl, "        ")
    if "hysteresis" in d:
        h = d["hysteresis"]
        kr, kru = _in(h["k_r_lb_in_per_rad"], "lb-in/rad", fam)
        out.append(f"  hysteresis (eqs 5.12-5.13): k_r {kr} {kru} "
                   f"(R² {h['r2']:.3f}){' ⚠' if h['flags'] else ''}, ξ_v "
                   f"{100 * h['damping_ratio']:.2f} %{' ⚠' if h['loop_flags'] else ''}")
        _warn_lines(out, h["loop_flags"])
    for k, why in d["skipped"].items():
        out.append(f"  skipped {k}: {why}")
    return "\n".join(out)
