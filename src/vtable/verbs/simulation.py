"""The virtual table's verbs: a command run on the multibody table (`simulate`), the
table written as MJCF (`export_mjcf`), and the built-in demonstration (`demo`: the EERC
configuration's modes, margins and x_t/x_c, and the SDOF frame under El Centro)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from vtable import display, units
from vtable.analytic import configs
from vtable.analytic.structure import storey_stiffnesses_of
from vtable.display import table_family
from vtable.effects.registry import parse_spec
from vtable.errors import VtableError
from vtable.mjcf.export import export_mjcf as export
from vtable.results import Demo, DemoSimulation, SimulationSummary, Written
from vtable.runs import write_run
from vtable.runs.model import with_noise
from vtable.signals import make_command
from vtable.signals.spectra import response_spectrum
from vtable.sim.experiment import load_specimen, load_table, run_experiment
from vtable.units import to_si
from vtable.verbs.analytic import margins_dict, modes_dict
from vtable.viz.rerun_scene import log_run

#: the channels of the peak table, each in its report unit (the JSON's)
PEAK_CHANNELS = [("h_span", "in"), ("avg_hdisp", "in"), ("pitch_disp", "rad"),
                 ("pitch_acc", "rad/s2"), ("acc_n_ne", "g"), ("pot_n_sw", "in"),
                 ("h1_force", "kip"), ("v1_force", "kip"), ("p1_stab", "kip")]


def exceedance_text(e, fam: str) -> str:
    """A limit exceedance as the report shows it, in the table's units (`vtable.display`)."""
    unit = {"stroke": "in", "velocity": "in/s", "force": "kip"}[e.quantity]
    return (f"{e.actuator} {e.quantity} {display.quantity(e.peak, unit, fam)} exceeds "
            f"{display.quantity(e.limit, unit, fam)} from t = {e.first_time:.3f} s")


def simulation_summary(exp, fam: str = "imperial") -> dict[str, Any]:
    """Peak table of a virtual-table experiment (report units, as the JSON holds it), the
    limits exceeded (in the units of `fam`), files and notes."""
    ch = exp.run.channels
    peaks = {k: {"peak": float(units.from_si(np.max(np.abs(ch[k])), u)), "unit": u}
             for k, u in PEAK_CHANNELS if k in ch}
    notes = list(exp.notes)
    h = getattr(exp.specimen, "hysteresis", None)
    if getattr(exp.specimen, "kind", "") == "opensees":  # every storey of the model
        k = 1
        while f"floor{k}_drift" in ch:
            for c, u in ((f"floor{k}_drift", "in"), (f"floor{k}_shear", "kip")):
                peaks[c] = {"peak": float(units.from_si(np.max(np.abs(ch[c])), u)), "unit": u}
            k += 1
    for k in (h.storeys if h is not None else ()):
        for c, u in ((f"floor{k}_drift", "in"), (f"floor{k}_shear", "kip")):
            if c in ch:
                peaks[c] = {"peak": float(units.from_si(np.max(np.abs(ch[c])), u)), "unit": u}
        if f"floor{k}_drift" in ch:
            u_y = h.of_storey(k, storey_stiffnesses_of(exp.specimen)[k - 1])[0]
            mu = float(np.max(np.abs(ch[f"floor{k}_drift"]))) / u_y
            notes.append(f"storey {k}: peak drift {mu:.2f} x its yield drift"
                         + (" (it yielded)" if mu > 1 else " (it stayed elastic)"))
    return {"peaks": peaks, "exceedances": [str(e) for e in exp.result.exceedances],
            "limits_shown": [exceedance_text(e, fam) for e in exp.result.exceedances],
            "shown_units": {k: exp.run.units[k] for k in peaks},
            "files": [str(f) for f in exp.files], "notes": notes}


#: the specimen `simulate` carries when none is chosen and the table's payload allows it
DEFAULT_SPECIMEN = "sdof_frame"
#: the default peak command (in) of each kind, before it is fitted to the table's limits
DEFAULT_PEAK_IN = {"earthquake": 4.0, "pulse": 1.0, "random": 0.25, "sine": 0.1}
#: the default random band (Hz), cut to the table's band
DEFAULT_BAND = (0.0, 25.0)
#: the share of the table's velocity and acceleration limits a default command may use
LIMIT_SHARE = 0.8
#: the share of the table's stroke a default command may use
STROKE_SHARE = 0.5


def _weight_text(mass_kg: float, fam: str) -> str:
    if fam == "metric":
        return display.quantity(mass_kg, "kg", fam, ".0f")
    return display.quantity(mass_kg * units.G, "kip", fam, ".1f")


def default_specimen(lab, fam: str) -> tuple[str, str]:
    """The specimen `simulate` carries when the user chose none: the SDOF frame when the
    table's payload carries it, else the bare table; and the one line saying why."""
    frame = load_specimen(DEFAULT_SPECIMEN)
    if lab.payload is None or frame.mass <= lab.payload:
        return DEFAULT_SPECIMEN, ""
    return "none", (f"specimen: none, the bare table (the SDOF frame's "
                    f"{_weight_text(frame.mass, fam)} exceeds {lab.name}'s payload of "
                    f"{_weight_text(lab.payload, fam)}; --specimen chooses one)")


def default_band(lab) -> tuple[tuple[float, float], str]:
    """The default random band, cut to the table's band, and the line saying so."""
    if lab.band is None or lab.band[1] >= DEFAULT_BAND[1]:
        return DEFAULT_BAND, ""
    band = (DEFAULT_BAND[0], float(lab.band[1]))
    return band, f"band {band[0]:g}-{band[1]:g} Hz: {lab.name}'s band (--band sets it)"


def command_peaks(cmd) -> tuple[float, float, float]:
    """Peak displacement (m), velocity (m/s) and acceleration (m/s²) of a command,
    differentiated from its samples (as the table's limits check them)."""
    v = np.gradient(cmd.x, cmd.t)
    a = np.gradient(v, cmd.t)
    return (float(np.max(np.abs(cmd.x))), float(np.max(np.abs(v))),
            float(np.max(np.abs(a))))


def fit_peak(lab, kind: str, make, fam: str) -> tuple[Any, str]:
    """The command of `kind` at its default peak, scaled down (if need be) so that its
    peak displacement is within STROKE_SHARE of the table's stroke and its peak velocity
    and acceleration, computed from the generated signal, within LIMIT_SHARE of the
    table's limits; the command and the line naming the limit that set it."""
    peak_in = DEFAULT_PEAK_IN[kind]
    cmd = make(peak_in)
    x, v, a = command_peaks(cmd)
    shares = [(STROKE_SHARE * lab.stroke / x if lab.stroke and x else np.inf, "stroke"),
              (LIMIT_SHARE * lab.velocity / v if lab.velocity and v else np.inf, "velocity"),
              (LIMIT_SHARE * lab.acceleration / a if lab.acceleration and a else np.inf,
               "acceleration")]
    scale, limit = min(shares)
    if scale >= 1.0:
        return cmd, ""
    peak_in *= scale
    cmd = make(peak_in)
    share = STROKE_SHARE if limit == "stroke" else LIMIT_SHARE
    given = units.to_si(peak_in, "in")
    shown = display.quantity(given, "in", fam)
    own = command_peaks(cmd)[0]
    part = ("" if abs(own - given) <= 0.005 * given else  # a cut earthquake: its own peak
             f", this part's own {display.quantity(own, 'in', fam)}")
    return cmd, (f"peak {shown}{part}: {share:.0%} of {lab.name}'s {limit} limit "
                 f"(--peak sets it: 2mm, 0.1in; a bare number is in "
                 f"{_UNIT_WORDS.get(length_unit(fam), length_unit(fam))})")


#: how a bare amplitude's unit is said
_UNIT_WORDS = {"in": "inches"}


def length_unit(fam: str) -> str:
    """The unit a bare amplitude is read in on a table of display family `fam`."""
    return display.unit_for("in", fam)


def peak_in_inches(peak, fam: str) -> float | None:
    """A peak a user gave (a `cli_args.Length`, or a number in the table's unit
    `length_unit`) in inches, the command generator's unit."""
    if peak is None:
        return None
    si = peak.si(length_unit(fam)) if hasattr(peak, "si") else \
        units.to_si(float(peak), length_unit(fam))
    return float(units.from_si(si, "in"))


def without_states(run):
    """The run without its internal `state_*` channels (which effects add and name)."""
    keep = [k for k in run.channels if not k.startswith("state_")]
    return dataclasses.replace(run, channels={k: run.channels[k] for k in keep},
                               units={k: u for k, u in run.units.items()
                                      if not k.startswith("state_")})


def simulate(specimen: str | None = None, kind: str = "random", *,
             duration: float | None = None, band: tuple[float, float] | None = None,
             peak: float | None = None, freq: float = 2.0, seed: int = 0,
             record: str | None = None, valve: str = "linear",
             effects: Sequence[str] = (), out: str | None = None, rerun: str | None = None,
             exaggerate: float = 50.0, table: str = "eerc",
             noise: float = 0.0, states: bool = False) -> SimulationSummary:
    """Run a command on the multibody virtual table of `table` (a preset name, or a TOML
    file with a [table] in the run format's keys; `effects`: 'name[:p=v,...]' added to the
    standard table); the peak table, limits and files written.

    What the user leaves out fits the table: `specimen` None is the SDOF frame, or the
    bare table when the table's payload cannot carry it (`default_specimen`); `band` None
    is 0-25 Hz cut to the table's band; `peak` None is the kind's default peak scaled to
    the table's stroke, velocity and acceleration (`fit_peak`); a `peak` given is a
    `cli_args.Length` or a number in the table's unit (in on the report's tables, mm on a
    metric one). Each choice is one line of the report. A value given explicitly is never
    changed: beyond a limit it is refused.
    `noise`: white Gaussian sensor noise, that fraction of each measured channel's RMS
    (`vtable.runs.with_noise`; the command channels clean, seeded by `seed`), added to
    the run written and said in its title — a campaign that looks like a lab's. The run
    file holds the run format's channels only, the same whatever the effects; `states`
    adds the model's internal states (`state_*` columns, which depend on them)."""
    if not (math.isfinite(noise) and 0.0 <= noise <= 1.0):
        raise VtableError(f"--noise: expected a fraction of each channel's RMS from 0 to 1, "
                          f"got {noise!r}")
    eff = dict(parse_spec(e) for e in effects)
    lab = load_table(table)
    fam = table_family(lab)
    vt = lab
    chosen = []
    if specimen is None:
        specimen, why = default_specimen(lab, fam)
        chosen.append(why)
    spec = load_specimen(specimen)
    if band is None:
        band, why = default_band(lab)
        chosen.append(why)

    def make(peak_in):
        return make_command(kind, duration=duration, band=tuple(band), peak_in=peak_in,
                            frequency=freq, seed=seed, record=record, unit=length_unit(fam))

    if peak is None and kind in DEFAULT_PEAK_IN:
        cmd, why = fit_peak(lab, kind, make, fam)
        chosen.append(why)
    else:
        cmd = make(peak_in_inches(peak, fam))
    exp = run_experiment(spec, cmd, vt=vt, valve=valve, effects=eff)
    exp.run.units = display.file_units(exp.run.units, fam)  # a metric table's: mm, g, kN
    if noise > 0:
        noisy = with_noise(exp.run, noise, seed=seed)
        exp.run = dataclasses.replace(noisy, meta={
            **noisy.meta, "title": f"{noisy.meta.get('title', '')}, {noise:.3g} x RMS white "
                                   f"sensor noise (seed {seed})"})
        exp.notes.append(f"sensor noise added: {noise:.3g} x each measured channel's RMS, "
                         f"seed {seed}")
    if out is not None:
        exp.run.name = str(out)
        exp.files += list(write_run(exp.run if states else without_states(exp.run), out))
    if rerun is not None:
        exp.files.append(log_run(exp.run, rerun, exaggeration=exaggerate))
    summary = simulation_summary(exp, fam)
    summary.update({"command": cmd.name, "specimen": spec.title,
                    "duration_s": float(exp.result.t[-1] - exp.result.t[0]),
                    "chosen": [c for c in chosen if c], "display": fam})
    return SimulationSummary(**summary)


def export_mjcf(specimen: str, out: str, table: str | None = None) -> Written:
    """The virtual table `table` (a preset or a TOML file, as `simulate --table` takes it;
    the EERC table when None) with `specimen` written to the folder `out` as MJCF and
    meshes."""
    vt = load_table(table)
    return Written([Path(f) for f in export(load_specimen(specimen), out, vt)])


def demo(out: str = "vtable-demo", simulate_too: bool = True) -> Demo:
    """The built-in EERC configuration: the hybrid model's coupled modes and margins, the
    peak and notch of x_t/x_c, and the SDOF frame on the virtual table under El Centro."""
    model = configs.load(configs.DEFAULT)
    model.check_stable()
    f = np.linspace(0.2, 15.0, 2961)
    xt, xe = np.abs(model.freqresp(f, "x_t", "x_c")), np.abs(model.freqresp(f, "x_eff", "x_c"))
    th = np.abs(model.freqresp(f, "theta_h", "x_c"))
    near = f < 5.0
    src, ref = configs.DEFAULT_REFERENCE
    d = {"configuration": configs.DEFAULT, **modes_dict(model),
         "reference": {"source": src, "modes": [{"f_hz": f, "damping": z} for f, z in ref]},
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
    for k in ("limits_shown", "shown_units"):  # the demo's run is the EERC table's: in, kip
        summary.pop(k)
    summary.update({
        "command": cmd.name, "duration_s": float(res.t[-1] - res.t[0]),
        "peak_x_t_in": float(np.max(np.abs(x_t)) / to_si(1, "in")),
        "peak_theta_h_in": float(np.max(np.abs(th * h)) / to_si(1, "in")),
        "peak_x_s_in": float(np.max(np.abs(x_s)) / to_si(1, "in")),
        "effective_spectrum_ratio": ratio, "spectrum_period_s": T_s})
    return DemoSimulation(**summary)
