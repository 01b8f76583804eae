"""The virtual table's verbs: a command run on the multibody table (`simulate`), the
table written as MJCF (`export_mjcf`), and the built-in demonstration (`demo`: the EERC
configuration's modes, margins and x_t/x_c, and the SDOF frame under El Centro)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vtable.analytic import configs
from vtable.effects.registry import parse_spec
from vtable.mjcf.export import export_mjcf as export
from vtable.params.virtual import virtual_table_for
from vtable.results import Demo, DemoSimulation, SimulationSummary, Written
from vtable.signals import make_command
from vtable.sim.experiment import load_specimen, load_table, run_experiment
from vtable.studies import response_spectrum
from vtable.units import to_si
from vtable.verbs.analytic import margins_dict, modes_dict
from vtable.viz.rerun_scene import log_run


def simulation_summary(exp) -> dict[str, Any]:
    """Peak table of a virtual-table experiment (report units)."""
    ch = {k: exp.channel(k) for k in exp.run.channels}
    keys = [("h_span", "in"), ("avg_hdisp", "in"), ("pitch_disp", "rad"), ("pitch_acc", "rad/s2"),
            ("acc_n_ne", "g"), ("pot_n_sw", "in"), ("h1_force", "kip"), ("v1_force", "kip"),
            ("p1_stab", "kip")]
    peaks = {k: {"peak": float(np.max(np.abs(ch[k]))), "unit": u} for k, u in keys if k in ch}
    return {"peaks": peaks, "exceedances": [str(e) for e in exp.result.exceedances],
            "files": [str(f) for f in exp.files], "notes": list(exp.notes)}


def simulate(specimen: str = "sdof_frame", kind: str = "random", *,
             duration: float | None = None, band: tuple[float, float] = (0.0, 25.0),
             peak: float | None = None, freq: float = 2.0, seed: int = 0,
             record: str | None = None, valve: str = "linear",
             effects: Sequence[str] = (), out: str | None = None, rerun: str | None = None,
             exaggerate: float = 50.0, table: str = "eerc") -> SimulationSummary:
    """Run a command on the multibody virtual table of `table` (a preset name, or a TOML
    file with a [table] in the run format's keys; `effects`: 'name[:p=v,...]' added to the
    standard table); the peak table, limits and files written."""
    eff = dict(parse_spec(e) for e in effects)
    lab = load_table(table)
    vt = virtual_table_for(lab)
    spec = load_specimen(specimen)
    if peak is None and lab.stroke is not None:  # the defaults, within the table's stroke
        default = {"earthquake": 4.0, "pulse": 1.0, "random": 0.25, "sine": 0.1}[kind] \
            if kind in ("earthquake", "pulse", "random", "sine") else None
        if default is not None and default * 0.0254 > 0.5 * lab.stroke:
            peak = 0.5 * lab.stroke / 0.0254
    cmd = make_command(kind, duration=duration, band=tuple(band), peak_in=peak,
                       frequency=freq, seed=seed, record=record)
    exp = run_experiment(spec, cmd, vt=vt, valve=valve, out=out, effects=eff)
    if rerun is not None:
        exp.files.append(log_run(exp.run, rerun, exaggeration=exaggerate))
    summary = simulation_summary(exp)
    summary.update({"command": cmd.name, "specimen": spec.title,
                    "duration_s": float(exp.result.t[-1] - exp.result.t[0])})
    return SimulationSummary(**summary)


def export_mjcf(specimen: str, out: str) -> Written:
    """The virtual table with `specimen` written to the folder `out` as MJCF and meshes."""
    return Written([Path(f) for f in export(load_specimen(specimen), out)])


def demo(out: str = "vtable-demo", simulate_too: bool = True) -> Demo:
    """The built-in EERC configuration: the hybrid model's coupled modes and margins, the
    peak and notch of x_t/x_c, and the SDOF frame on the virtual table under El Centro."""
    model = configs.load(configs.DEFAULT)
    model.check_stable()
    f = np.linspace(0.2, 15.0, 2961)
    xt, xe = np.abs(model.freqresp(f, "x_t", "x_c")), np.abs(model.freqresp(f, "x_eff", "x_c"))
    th = np.abs(model.freqresp(f, "theta_h", "x_c"))
    near = f < 5.0
    d = {"configuration": configs.DEFAULT, **modes_dict(model),
         "margins": margins_dict(model, "x_t", "x_c"),
         "x_t/x_c": {"peak": float(xt[near].max()),
                     "f_peak_hz": float(f[near][xt[near].argmax()]),
                     "notch": float(xt[near].min()),
                     "f_notch_hz": float(f[near][xt[near].argmin()])},
         "x_eff/x_c notch_hz": float(f[near][xe[near].argmin()]),
         "theta_h/x_c peak_hz": float(f[near][th[near].argmax()])}
    if simulate_too:
        d["simulation"] = _demo_simulation(out)
    return Demo.from_dict(d)


def _demo_simulation(out: str) -> DemoSimulation:
    spec = load_specimen("sdof_frame")
    cmd = make_command("earthquake")
    exp = run_experiment(spec, cmd, out=f"{out}/sdof_elcentro")
    exp.files.append(log_run(exp.run, f"{out}/sdof_elcentro.rrd"))
    res = exp.result
    h = exp.result.built.structure_heights[-1]
    x_t, th = res.joint("x"), res.joint("pitch")
    x_s = res.joint("x_s")
    dt = res.t[1] - res.t[0]
    a_eff = res.joint("x", "qacc") + h * res.joint("pitch", "qacc")
    T_s = 1 / spec.frequency
    periods = np.array([T_s])
    ratio = float(response_spectrum(a_eff, dt, periods, 0.05).psa[0]
                  / response_spectrum(res.command_acc, dt, periods, 0.05).psa[0])
    summary = simulation_summary(exp)
    summary.update({
        "command": cmd.name, "duration_s": float(res.t[-1] - res.t[0]),
        "peak_x_t_in": float(np.max(np.abs(x_t)) / to_si(1, "in")),
        "peak_theta_h_in": float(np.max(np.abs(th * h)) / to_si(1, "in")),
        "peak_x_s_in": float(np.max(np.abs(x_s)) / to_si(1, "in")),
        "effective_spectrum_ratio": ratio, "spectrum_period_s": T_s})
    return DemoSimulation(**summary)
