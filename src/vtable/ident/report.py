"""What `vtable identify` computes for a run: the servo-loop fit, Table 3.1, springs from
frequencies, rocking impedance, hysteresis (report units in the output).

Each section is its own guarded step: one that cannot be made (a channel absent, zero or
constant, a record too short for the mode, a fit that fails) is listed under `skipped`
with the reason, and the others are still made. Every fitted number carries its validity
flags (vtable.ident.validity); numbers derived from flagged fits inherit them. Notes say
what was assumed (no [specimen], a table without pitch).

The table is the run's own (`vtable.runs.lab.run_table`: its [table], the EERC table
when it has none): the platen mass m_t of eq 7.9's mass ratio u = m_s/m_t and of the
springs of eqs 5.15-5.16, its DOFs (the pitch sections are skipped, with the reason, on
a table that does not pitch), its valve time constant τ (eq 6.15 x a first-order valve
lag, τ fitted beside (f_o, ξ_o, k_o); eq 7.9 with τ held) and its described loop (eq
6.16, the starting point of the fits). Before any eq 6.15 parameter is quoted, the loop's
structure is checked (`vtable.ident.loop.compare_structures`): a loop whose DC gain is not
1, or which a type-0 loop fits better, is reported as not fitting eq 6.15, with the
structure that does.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from vtable import units
from vtable.analytic import closed_forms
from vtable.display import run_family
from vtable.errors import VtableError
from vtable.ident import channels
from vtable.ident.fits import Fit, fit_open_loop, fit_table_sdof
from vtable.ident.frames import MIN_AVERAGES, frame_for_averages, frame_for_mode
from vtable.ident.loop import STRUCTURES, LoopData, compare_structures, prior_of
from vtable.ident.result import Identification
from vtable.ident.structure import (
    ModalEstimate,
    fixed_base,
    fully_coupled,
    hysteresis,
    pitch_channel,
    pitch_is_zero,
    pitch_moment,
    rocking_coupled,
    rocking_impedance,
    rocking_springs_fit,
)
from vtable.ident.tf import TransferFunction, transfer_function
from vtable.ident.validity import Flag, flags_json, inherit, loop_flags, settled
from vtable.params.loops import OpenLoop
from vtable.params.specimen import NoSpecimen, RigidBlock, SDOFSpecimen, ShearBuilding
from vtable.params.virtual import VirtualTable
from vtable.runs.channels import FORMAT_UNITS
from vtable.runs.lab import run_table
from vtable.runs.model import Run
from vtable.tables.lab import bare_loop
from vtable.units import to_si

#: the servo-loop fits use this band (the report's 0-25 Hz random tests), widened to 1.5
#: times the described f_o (below 0.45 fs) for a table whose loop lies above it
SERVO_BAND = (0.2, 25.0)


def servo_band(run: Run, table: VirtualTable) -> tuple[float, float]:
    """The band of the servo-loop fits: `SERVO_BAND`, its top raised to 1.5 f_o of the
    table's described loop (eq 6.16) and kept below 0.45 fs."""
    hi = max(SERVO_BAND[1], 1.5 * bare_loop(table).f_o)
    return SERVO_BAND[0], min(hi, 0.45 * run.fs)


def _fit_dict(fit: Fit | None) -> dict[str, Any] | None:
    return None if fit is None else fit.to_json()


def _no_pitch(table: VirtualTable) -> str:
    return f"the {table.name} table does not pitch (its DOFs: {', '.join(table.dofs)})"


def _section(out: Identification, name: str, step: Callable[[], None]) -> None:
    """Run one section; a VtableError skips it with its message (anything else is a bug
    and propagates)."""
    try:
        step()
    except VtableError as e:
        out.skipped[name] = str(e)


def _unusable_channels(run: Run) -> list[str]:
    """The format's channels present but zero or constant throughout."""
    out = []
    for name in FORMAT_UNITS:
        why = channels.channel_problem(run, name) if run.has(name) else None
        if why and ("zero" in why or "constant" in why):
            out.append(why)
    return out


def identify_run(run: Run) -> Identification:
    """Everything identifiable from the run's channels on the run's table
    (`vtable.runs.lab.run_table`), each section in its own guarded step; sections that
    cannot be made (a channel absent, a DOF the table does not have, a fit that fails)
    are listed under `skipped` with the reason.

    Parameters
    ----------
    run
        A run as read, aligned when its drive file's offset is "auto"
        (`vtable.ident.drive.align`: the command h_span is then made).

    Returns
    -------
    Identification
        The sections (report units), ``notes`` and ``skipped``; ``to_json()`` for the
        JSON record, ``report()`` for the printed text.
    """
    out = Identification(run=run.name, fs_hz=run.fs, duration_s=run.duration,
                         reports=list(run.reports), display=run_family(run))
    notes = out.notes
    spec = run.specimen()
    if run.declared.specimen is None:
        notes.append("no [specimen]: identified as a bare table")
    table = run_table(run)
    out.table = {"name": table.name, "dofs": list(table.dofs),
                 "platen_mass_kg": table.platen_mass,
                 "horizontal_actuators": table.n_actuators,
                 "valve_time_constant_s": table.valve_lag}
    if run.declared.table is None:
        notes.append("no [table]: the EERC table assumed (the format's default)")
    notes.extend(_unusable_channels(run))
    m_t = table.platen_mass

    _section(out, "servo loop fit", lambda: _servo_loop(run, spec, m_t, table, out))
    notes.extend(unit_hints(run, out))
    rows: dict[str, ModalEstimate] = {}
    if isinstance(spec, SDOFSpecimen):
        out.table_3_1, out.table_3_1_methods = [], {}
        if pitch_is_zero(run):
            notes.append("pitch_acc is zero throughout: taken as a table without pitch "
                         "(x_eff = x_t)")
        why = channels.channel_problem(run, "h_span")
        if why:
            notes.append(f"{why}: H_f and H_r are H1 estimates with x_eff and x_t as inputs "
                         "(sensor noise biases them near the fixed-base notch of x_eff)")
        _section(out, "table 3.1: fixed base",
                 lambda: _row(out, rows, "fixed", fixed_base(run)))
        if table.pitches:
            _section(out, "table 3.1: base rotation coupling", lambda: _row(
                out, rows, "rocking", rocking_coupled(run, *_after(rows, "fixed"))))
        else:
            out.skipped["table 3.1: base rotation coupling"] = _no_pitch(table)
        coupled = ("transl. and rot. coupling" if table.pitches
                   else "translational coupling")  # the table cannot pitch
        _section(out, f"table 3.1: {coupled}", lambda: _row(
            out, rows, "coupled", fully_coupled(
                run, *_after(rows, "rocking" if "rocking" in rows else "fixed"),
                name=coupled)))
        _section(out, "springs from frequencies", lambda: _springs(spec, rows, out))
    else:
        out.skipped["table 3.1"] = (
            f"needs a sdof specimen, the run has {spec.kind}" +
            (" (shear buildings: vtable.ident.structure.table_3_1)"
             if isinstance(spec, ShearBuilding) else ""))
    at: dict[str, Any] = {}
    if table.pitches:
        _section(out, "rocking impedance", lambda: _rocking(run, rows, out, at))
        _section(out, "hysteresis", lambda: _hysteresis(run, out, at))
    else:
        out.skipped["rocking impedance"] = _no_pitch(table)
        out.skipped["hysteresis"] = _no_pitch(table) + ": no moment-rotation loop"
    return out


# ---- plausibility of the declared units -------------------------------------------------
#: a loop fit below this R² on a run whose displacement and command disagree in scale
#: calls for a look at the declared units
POOR_LOOP_R2 = 0.5
LENGTHS = ("m", "cm", "mm", "in", "ft")
LENGTH_NAMES = {"m": "metres", "cm": "centimetres", "mm": "millimetres", "in": "inches",
                "ft": "feet"}


def unit_hints(run: Run, out: Identification) -> list[str]:
    """When the loop fit (eq 6.15 or 7.9) has R² < `POOR_LOOP_R2`, or could not be made,
    and x_t's RMS is ≥ 5× or ≤ 1/5 of x_c's (a servo loop tracks its command within a
    factor of ~2 in its band), name the length unit that would bring them together: a
    displacement declared in mm but written in inches reads 25.4× small."""
    fit = out.open_loop or out.table_sdof
    if fit is not None and fit["r2"] >= POOR_LOOP_R2:
        return []
    if "h_span" not in run.channels or "avg_hdisp" not in run.channels:
        return []
    x_c, x_t = run.channels["h_span"], run.channels["avg_hdisp"]
    rc, rt = float(np.std(x_c)), float(np.std(x_t))
    if not (rc > 0 and rt > 0) or 0.2 < rt / rc < 5:
        return []
    declared = run.units.get("avg_hdisp", "in")
    if declared not in LENGTHS:
        return []
    # if x_t were in unit v, its SI values would be ratio x factor(v)/factor(declared)
    k = to_si(1.0, declared)
    best = min(LENGTHS, key=lambda v: abs(np.log(rt / rc * to_si(1.0, v) / k)))
    fit_text = "could not be made" if fit is None else f"fits with R² {fit['r2']:.2f}"
    return [f"avg_hdisp is declared {declared}; its RMS is {rt / rc:.3g}× the command's "
            f"(h_span, {run.units.get('h_span', 'in')}) and the loop {fit_text}: is it in "
            f"{LENGTH_NAMES[best]}? ([units] avg_hdisp = \"{best}\")"]


# ---- the servo loop -------------------------------------------------------------------
#: the digital stage's terms (`vtable.controllers.kinds.digital`) by their run-format names
_TERMS = (("i", "i_per_s"), ("d", "d_s"), ("t_v", "feedforward_velocity_s"),
          ("t_a", "feedforward_acceleration_s2"), ("k_a", "acceleration_gain_v_s2_per_m"),
          ("ref", "reference generator"))


def _controller_terms(table: VirtualTable) -> list[str]:
    """The declared controller's terms beyond the P law (eqs 6.1-6.4) that are on."""
    if table.control is None:
        return []
    p = table.control.params
    on = [name for key, name in _TERMS if p.get(key, 0.0)]
    if p.get("n1_zz", 1.0) != p.get("n1_zp", 1.0):  # a declared notch (ζ_z < ζ_p)
        on.append("notch")
    return on


def _servo_loop(run: Run, spec, m_t: float, table: VirtualTable, out: Identification) -> None:
    """x_t/x_c: eq 6.15 (bare table, rigid mass; x a first-order valve lag when the
    table has a valve time constant), checked against the other loop structures first,
    or eq 7.9 (a SDOF structure, the valve lag held)."""
    x_c, x_t = channels.require(run, "h_span", "avg_hdisp", purpose="the servo-loop fit x_t/x_c")
    n_samples = len(run.time)
    band = servo_band(run, table)
    tau = table.valve_lag
    if isinstance(spec, NoSpecimen | RigidBlock):
        # a broad loop resonance (ξ_o ~ 0.5): frames for averages, the report's 2048 at most
        n = frame_for_averages(n_samples, MIN_AVERAGES, longest=2048) or \
            frame_for_averages(n_samples, 2)
        if n is None:
            raise VtableError(f"{run.name}: {run.duration:.1f} s is too short for a transfer "
                              "function with 2 averages")
        tf = transfer_function(x_c, x_t, run.fs, n)
        ls = compare_structures(LoopData.from_tf(tf, band), prior_of(table))
        out.loop_structure = ls.to_json()
        if not ls.fits_eq_6_15:
            raise VtableError(ls.why + "; its eq 6.15 parameters would not be physical")
        if ls.best == "resonator":  # a resonance the run does not declare, fitted with it
            fit = ls.fits["resonator"]
            what = f"{STRUCTURES['resonator'].name} fit"
        elif "declared" in ls.fits:  # the declared controller's terms held, the loop fitted
            fit = ls.fits["declared"]
            what = f"the declared {table.controller} controller's loop fit"
        elif tau > 0:  # the table's valve lag: eq 6.15 x 1/(1 + τs), τ fitted
            fit = ls.fits["eq_6_15_lag"]
            what = f"{STRUCTURES['eq_6_15_lag'].name} fit"
        else:
            fit = fit_open_loop(tf.f, tf.H, tf.coherence, band=band).checked(
                averages=tf.averages)
            what = "eq 6.15 fit"
        ol = OpenLoop(f_o=fit["f_o"], xi_o=fit["xi_o"], k_o=fit["k_o"])
        derived = inherit(fit.flags, what)
        d = _fit_dict(fit)
        d["model"] = what.removesuffix(" fit")
        d["band_hz"] = list(band)
        if ls.best == "resonator":
            m_s = fit["u"] * m_t
            d["note_resonator"] = (
                f"x_t/x_c has the peak and notch of a resonance on the platen that the run "
                f"does not declare: f_s {fit['f_s']:.2f} Hz, ξ_s {fit['xi_s']:.3f}, mass "
                f"ratio u {fit['u']:.3f} (about {m_s:.0f} kg on the {m_t:.0f} kg platen); the "
                "loop is quoted with it held. Declare the specimen ([specimen] sdof) or "
                "diagnose with the platen_resonator effect")
        d["gain_margin"] = closed_forms.gain_margin_bare(ol)
        d["gain_margin_flags"] = flags_json(derived)
        out.open_loop = d
        mass = m_t + (spec.mass if isinstance(spec, RigidBlock) else 0.0)
        f = np.array([2.0, 5.0, 10.0])
        k_h, c_h = closed_forms.feedback_spring(mass, ol, f)  # eqs 5.15-5.16
        out.horizontal_spring = {
            "f_hz": f.tolist(), "k_h_kip_per_in": units.from_si(k_h, "kip/in").tolist(),
            "c_h_lb_s_per_in": units.from_si(c_h, "lb-s/in").tolist(),
            "equations": "5.15, 5.16", "flags": flags_json(derived),
            "mass_kg": mass,
            **({"note": f"eqs 5.15-5.16 have no valve lag: τ {fit['tau']:.3g} s left out"}
               if tau > 0 else {})}
    elif isinstance(spec, SDOFSpecimen):
        u = spec.mass / m_t

        def fit_on(n: int) -> tuple[Fit, TransferFunction]:
            tf = transfer_function(x_c, x_t, run.fs, n)
            return fit_table_sdof(tf.f, tf.H, u, tf.coherence, band=band, tau=tau).checked(
                averages=tf.averages), tf

        what = "eq 7.9 fit (the notch of f_s, ξ_s)"
        choice = frame_for_mode(n_samples, run.fs, spec.frequency, spec.damping, what)
        fit, _ = fit_on(choice.nperseg)
        try:  # once more on frames for the fitted (f_s, ξ_s), if they are sound
            again = frame_for_mode(n_samples, run.fs, fit["f_s"],
                                   min(max(fit["xi_s"], 1e-4), 0.5), what)
            if again.nperseg != choice.nperseg and settled(fit, ("f_s", "xi_s")):
                fit, _ = fit_on(again.nperseg)
                choice = again
        except VtableError:
            pass
        d = _fit_dict(fit)
        d["frame"] = choice.why
        d["mass_ratio"] = u
        d["table_mass_kg"] = m_t
        if tau > 0:
            d["valve_lag_s"] = tau
            d["note_valve"] = (f"eq 7.9 with the valve lag τ {tau:g} s of the table's "
                               "description held in the loop")
        held = _controller_terms(table)
        if held:
            d["note_controller"] = (
                f"eq 7.9 is the report's P loop: the declared {table.controller} controller's "
                f"own terms ({', '.join(held)}) are not in this fit, so its k_o is an "
                "effective one")
        if channels.usable(run, "pitch_acc"):
            d["note"] = ("eq 7.9 has no pitch: on a pitching table f_s, ξ_s are the "
                         "structure's on the rocking table (compare Table 3.1's base "
                         "rotation coupling)")
        out.table_sdof = d
    else:
        raise VtableError("eq 6.15 is for a bare table or a rigid mass and eq 7.9 for a sdof "
                          f"structure; no servo-loop model for a {spec.kind}")


# ---- Table 3.1 and the springs ----------------------------------------------------------
def _after(rows: dict[str, ModalEstimate], key: str) -> tuple[float, float]:
    """(f, ξ) of an earlier row to start the next from."""
    if key not in rows:
        raise VtableError(f"needs the {key} row, which was skipped")
    e = rows[key]
    xi = float(min(max(e.xi, 1e-3), 0.5)) if np.isfinite(e.xi) else 0.02
    return e.f, xi


def _row(out: Identification, rows: dict[str, ModalEstimate], key: str,
         e: ModalEstimate) -> None:
    rows[key] = e
    p = e.primary
    out.table_3_1.append({
        "case": e.name, "f_hz": e.f, "damping": e.xi, "method": p.method,
        "nperseg": 2 * (e.tf.f.size - 1), "averages": e.tf.averages,
        "resolution_hz": e.tf.resolution_hz,
        "frame": e.frame.why if e.frame else "given --nperseg",
        "flags": flags_json(p.flags)})
    out.table_3_1_methods[e.name] = {
        "primary": _fit_dict(p), "appendix_d": _fit_dict(e.amplitude),
        "circle": _fit_dict(e.circle), "skipped": dict(e.skipped)}


def _springs(spec: SDOFSpecimen, rows: dict[str, ModalEstimate], out: Identification) -> None:
    """k_r (eq 5.4) from the fixed-base and rocking-coupled frequencies, k_h (eq 5.5)
    with the coupled one, as a `Fit` whose standard errors propagate the frequencies'
    (k_r is undetermined when f_f and f_r differ by less than their errors); the
    frequencies' flags carry over."""
    for k in ("fixed", "rocking", "coupled"):
        if k not in rows:
            raise VtableError(f"needs the three Table 3.1 frequencies; the {k} row was skipped")
    est = [rows["fixed"], rows["rocking"], rows["coupled"]]

    def springs(f: np.ndarray) -> np.ndarray:
        k_r = closed_forms.rocking_stiffness_from_frequencies(f[0], f[1], spec.mass, spec.height)
        return np.array([k_r, closed_forms.horizontal_stiffness_from_frequencies(
            f[0], f[2], spec.mass, spec.height, k_r)])

    f = np.array([e.f for e in est])
    sf = np.array([e.primary.stderr.get("f_n", np.nan) for e in est])
    k = springs(f)
    J = np.empty((2, 3))
    for i in range(3):  # central differences, steps well inside the frequencies' spacing
        h = 1e-7 * f[i]
        J[:, i] = (springs(f + h * np.eye(3)[i]) - springs(f - h * np.eye(3)[i])) / (2 * h)
    sk = np.sqrt((J**2) @ sf**2)
    fit = Fit({"k_r": float(k[0]), "k_h": float(k[1])},
              {"k_r": float(sk[0]), "k_h": float(sk[1])}, float("nan"), float("nan"), 3,
              "eqs 5.4, 5.5 from the Table 3.1 frequencies").checked()
    flags: list[Flag] = list(fit.flags)
    for e in est:
        flags += inherit(e.primary.flags, e.name, params=("f_n",))
    out.springs_from_frequencies = {
        "k_r_lb_in_per_rad": units.from_si(k[0], "lb-in/rad"),
        "k_h_kip_per_in": units.from_si(k[1], "kip/in"),
        "stderr": {"k_r_lb_in_per_rad": units.from_si(sk[0], "lb-in/rad"),
                   "k_h_kip_per_in": units.from_si(sk[1], "kip/in")},
        "equations": "5.4, 5.5", "flags": flags_json(flags)}


# ---- rocking impedance and hysteresis ----------------------------------------------------
def pitch_resonance(run: Run) -> tuple[float, list[Flag]]:
    """Where the table pitches most per unit input, 0.5-20 Hz: the peak of |θ/x_c|
    (θ/M without the command), over lines with coherence >= 0.5 and above the Hann
    window's main lobe around 0 Hz (3 lines)."""
    c = pitch_channel(run)
    x = run.channels["h_span"] if channels.usable(run, "h_span") else pitch_moment(run)
    n = frame_for_averages(len(run.time), MIN_AVERAGES) or frame_for_averages(len(run.time), 2)
    if n is None:
        raise VtableError(f"{run.name}: too short to locate the pitch resonance")
    th = transfer_function(x, run.channels[c], run.fs, n)
    p = 2 if c == "pitch_acc" else 0
    df = th.f[1] - th.f[0]
    band = (th.f >= max(0.5, 3 * df)) & (th.f <= 20.0) & (th.coherence >= 0.5)
    if band.sum() < 3:
        raise VtableError(f"{run.name}: no coherent pitch response in 0.5-20 Hz to evaluate "
                          "G_r at")
    fb = th.f[band]
    amp = np.abs(th.H[band]) / fb**p
    i = int(np.argmax(amp))
    if i in (0, len(fb) - 1):
        raise VtableError(f"{run.name}: the pitch response has no peak inside "
                          f"{fb[0]:.3g}-{fb[-1]:.3g} Hz (largest at {fb[i]:.3g} Hz, the edge): "
                          "no frequency to evaluate G_r at")
    flags = []
    if th.averages < MIN_AVERAGES:
        flags.append(Flag("few_averages", f"pitch resonance located with {th.averages} "
                          "averages"))
    return float(fb[i]), flags


def _rocking(run: Run, rows: dict[str, ModalEstimate], out: Identification,
             at: dict[str, Any]) -> None:
    """G_r = M/θ at the coupled frequency (or the pitch resonance without Table 3.1),
    total and by group (eqs 5.9-5.11)."""
    c = pitch_channel(run)
    if "coupled" in rows:
        f_eval = rows["coupled"].f
        # G_r is smooth in ω: only a flagged frequency itself carries over
        base = inherit(rows["coupled"].primary.flags, "coupled frequency", params=("f_n",),
                       whole_fit=False)
        where = "the Table 3.1 coupled frequency"
    else:
        f_eval, base = pitch_resonance(run)
        where = "the pitch resonance of θ/x_c"
    d: dict[str, Any] = {"f_hz": f_eval, "at": where, "theta_from": c, "skipped": {}}
    for g, grp in (("total", ("vertical", "stabilizer")), ("vertical actuators", ("vertical",)),
                   ("stabilizers", ("stabilizer",))):
        try:
            fit = rocking_springs_fit(rocking_impedance(run, groups=grp), f_eval, "G_r")
        except VtableError as e:
            if g == "total":
                raise
            d["skipped"][g] = str(e)
            continue
        d[g] = {"k_r_lb_in_per_rad": units.from_si(fit["k_r"], "lb-in/rad"),
                "c_r_lb_in_s_per_rad": units.from_si(fit["c_r"], "lb-in-s/rad"),
                "stderr": {"k_r_lb_in_per_rad": units.from_si(fit.stderr["k_r"], "lb-in/rad"),
                           "c_r_lb_in_s_per_rad": units.from_si(fit.stderr["c_r"],
                                                                "lb-in-s/rad")},
                "coherence": fit.context.get("coherence"), "averages": fit.context["averages"],
                "flags": flags_json([*fit.flags, *base])}
    out.rocking_impedance = d
    at["f"], at["flags"] = f_eval, base


def _hysteresis(run: Run, out: Identification, at: dict[str, Any]) -> None:
    """Eqs 5.12-5.13 on the moment-rotation loop at the G_r frequency."""
    (th,) = channels.require(run, "pitch_disp", purpose="the moment-rotation loop")
    if "f" not in at:
        raise VtableError("needs the rocking-impedance frequency (that section was skipped)")
    f_eval, base = at["f"], at["flags"]
    h = hysteresis(th, pitch_moment(run), run.dt, f_eval)
    reg = h.fit
    loop = loop_flags(h.crest_factor, f_eval)
    k_flags = [*(reg.flags if reg else ()), *base]
    out.hysteresis = {
        "f_hz": f_eval,
        "k_r_lb_in_per_rad": units.from_si(h.stiffness, "lb-in/rad"),
        "k_r_stderr_lb_in_per_rad": units.from_si(reg.stderr["k"], "lb-in/rad"),
        "r2": reg.r2,
        "c_r_lb_in_s_per_rad": units.from_si(h.damping_coefficient, "lb-in-s/rad"),
        "damping_ratio": h.damping_ratio, "crest_factor": h.crest_factor,
        "equations": "5.12-5.13", "flags": flags_json(k_flags),
        "loop_flags": flags_json([*loop, *k_flags])}
