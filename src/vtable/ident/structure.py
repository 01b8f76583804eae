"""The structure on the table (report §3.3, §4.2, §5.3-5.6): effective base motion,
fixed-base / rocking-coupled / coupled frequency and damping (Table 3.1), the rocking
impedance G_r = M/θ from the actuator forces, hysteresis loops, springs."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg

from vtable import units
from vtable.analytic import closed_forms
from vtable.analytic.structure import modal_damping, specimen_frequencies
from vtable.errors import VtableError
from vtable.ident import channels
from vtable.ident.fits import Fit, amplitude_fit, circle_fit, fit_mode
from vtable.ident.frames import FrameChoice, frame_for_mode
from vtable.ident.tf import TransferFunction, transfer_function, transfer_function_via
from vtable.ident.validity import settled
from vtable.params.specimen import RigidBlock, SDOFSpecimen, ShearBuilding
from vtable.runs.lab import run_table
from vtable.runs.model import Run

TWO_PI = 2 * np.pi
IN = units.to_si(1.0, "in")
#: actuator positions of the run format (x, y in inches from the table centre)
V_POS = {1: (72, 72), 2: (-72, 72), 3: (-72, -72), 4: (72, -72)}
P_POS = {1: (102, 102), 2: (-102, 102), 3: (-102, -102), 4: (102, -102)}


def effective_height(run: Run, bare: float | None = None) -> float:
    """h of x_eff = x_t + hθ: the SDOF top mass (eq 3.5), a rigid block's centre of
    gravity, or a shear building's first-mode effective height (eq 4.24); for a bare table
    `bare` when given (what needs no height: the table's own motion), else an error."""
    spec = run.specimen()
    if isinstance(spec, SDOFSpecimen | RigidBlock):
        return spec.height
    if isinstance(spec, ShearBuilding):
        return closed_forms.effective_height_first_mode(spec.masses, spec.heights)
    if bare is not None:
        return bare
    raise VtableError(f"{run.name}: a bare table has no effective height (x_t + θh at a "
                      "specimen): --objective table drives the table's motion x_t")


def lowest_declared_mode(run: Run) -> tuple[float, float] | None:
    """(f Hz, ξ) of the lowest fixed-base mode of the run's declared specimen (ξ at least
    0.001), or None: no specimen declared, or one without modes. What frames must resolve
    to show the peak and notch the report is about (`vtable tf`, the report's Bode
    plots)."""
    spec = run.declared.specimen
    if isinstance(spec, SDOFSpecimen):
        return spec.frequency, max(spec.damping, 1e-3)
    if isinstance(spec, ShearBuilding):
        return min(specimen_frequencies(spec)), max(float(modal_damping(spec)[0]), 1e-3)
    return None


def accelerations(run: Run) -> dict[str, np.ndarray]:
    """Table, effective (eq 4.11/4.13) and top-mass accelerations (m/s²).

    A pitch_acc of zeros (a table without pitch) gives x_eff = x_t; `pitch_is_zero`
    tells the caller, which must say so. On a table whose DOFs have no pitch (the run's
    [table], `vtable.runs.lab.run_table`) x_eff = x_t without a pitch channel."""
    h = effective_height(run)
    (a_t,) = channels.require(run, "avg_hacc", purpose="the table motion")
    if not run.has("pitch_acc") and not run_table(run).pitches:
        a_th = np.zeros_like(a_t)
    elif channels.channel_problem(run, "pitch_acc") in (None, "pitch_acc is zero throughout"):
        a_th = run.channels["pitch_acc"]
    else:
        (a_th,) = channels.require(run, "pitch_acc", purpose="the effective motion x_t + hθ")
    tops = channels.require_any(run, ("acc_n_ne", "acc_n_nw"),
                                purpose="the top-mass acceleration")
    a_top = np.mean(tops, axis=0)
    a_eff = a_t + h * a_th
    return {"table": a_t, "pitch": a_th, "effective": a_eff, "top": a_top,
            "relative": a_top - a_eff}


def pitch_is_zero(run: Run) -> bool:
    return run.has("pitch_acc") and not run.missing.get("pitch_acc") and \
        not np.any(run.channels["pitch_acc"])


def default_frame(run: Run, averages: int = 15, longest: int = 16384) -> int:
    """The longest power-of-two frame giving at least `averages` averages at 50 %
    overlap (the report used 2048 points and 40 averages, §3.2)."""
    n = len(run.time)
    k = 2 ** int(np.floor(np.log2(max(2 * n / (averages + 1), 64))))
    return int(min(k, longest))


@dataclass(frozen=True)
class ModalEstimate:
    """One frequency/damping estimate from a transfer function: the primary fit, the
    other methods for comparison (appendix D amplitude fit, circle fit; None with the
    reason in `skipped` when they could not be made) and the frame it used."""

    name: str
    tf: TransferFunction
    primary: Fit
    amplitude: Fit | None
    circle: Fit | None
    frame: FrameChoice | None = None
    skipped: dict[str, str] = field(default_factory=dict)

    @property
    def f(self) -> float:
        return self.primary.params["f_n"]

    @property
    def xi(self) -> float:
        return self.primary.params["xi_n"]


def _modal(name: str, tf: TransferFunction, f_guess: float, power: int,
           complex_fit: bool) -> ModalEstimate:
    """Fit the mode near f_guess; |H|/ω^power has appendix D's form (eq D.2). Every fit
    is checked (vtable.ident.validity) with the estimate's averages."""
    w = TWO_PI * tf.f
    with np.errstate(divide="ignore", invalid="ignore"):
        R = np.where(tf.f > 0, tf.H / w**power, np.nan)
    mag = np.abs(R)
    near = (tf.f > 0.6 * f_guess) & (tf.f < 1.5 * f_guess) & np.isfinite(mag)
    if not near.any():
        raise VtableError(f"{name}: no data near {f_guess:.3g} Hz")
    fp = float(tf.f[near][np.nanargmax(mag[near])])
    skipped: dict[str, str] = {}
    try:
        amp = amplitude_fit(tf.f, mag, "A3", band=(0.75 * fp, 1.25 * fp),
                            coherence=tf.coherence).checked(averages=tf.averages)
    except VtableError as e:
        amp, skipped["appendix D"] = None, str(e)
    fa = amp.params["f_n"] if amp is not None and 0.75 * fp < amp.params["f_n"] < 1.25 * fp \
        else fp
    try:
        circ = circle_fit(tf.f, R, (fa * 0.9, fa * 1.1)).checked(averages=tf.averages)
    except VtableError as e:
        circ, skipped["circle fit"] = None, str(e)
    if complex_fit:
        primary = fit_mode(tf.f, R, (0.85 * fa, 1.15 * fa), tf.coherence,
                           power=0).checked(averages=tf.averages)
    elif amp is None:
        raise VtableError(f"{name}: {skipped['appendix D']}")
    else:
        primary = amp
    return ModalEstimate(name, tf, primary, amp, circ, skipped=skipped)


def _estimate(name: str, run: Run, make_tf: Callable[[int], TransferFunction],
              f_guess: float, xi_guess: float, power: int, complex_fit: bool,
              nperseg: int | None) -> ModalEstimate:
    """A mode fitted on frames chosen for it (vtable.ident.frames): first for the guess
    (f, ξ), then once more for the fitted (f, ξ) if that calls for another frame and the
    first fit is sound enough to go by (`validity.settled`). A given `nperseg` is used
    as is (its validity is still checked)."""
    n_samples = len(run.time)
    if nperseg:
        return _modal(name, make_tf(nperseg), f_guess, power, complex_fit)
    choice = frame_for_mode(n_samples, run.fs, f_guess, xi_guess, name)
    est = replace(_modal(name, make_tf(choice.nperseg), f_guess, power, complex_fit),
                  frame=choice)
    if not settled(est.primary, ("f_n", "xi_n")):  # a fit to choose nothing from
        return est
    try:
        again = frame_for_mode(n_samples, run.fs, est.f, min(max(est.xi, 1e-4), 0.5), name)
    except VtableError:
        return est
    if again.nperseg == choice.nperseg:
        return est
    try:
        return replace(_modal(name, make_tf(again.nperseg), est.f, power, complex_fit),
                       frame=again)
    except VtableError:
        return est


@dataclass(frozen=True)
class Table31:
    """Report Table 3.1 for one run: fixed base (H_f, eq 5.1), base-rotation coupling
    (H_r, eq 5.2) and translation + rotation coupling (H_hr, eq 5.3)."""

    fixed: ModalEstimate
    rocking: ModalEstimate
    coupled: ModalEstimate

    def rows(self) -> list[tuple[str, float, float]]:
        return [("fixed base", self.fixed.f, self.fixed.xi),
                ("base rotation coupling", self.rocking.f, self.rocking.xi),
                ("transl. and rot. coupling", self.coupled.f, self.coupled.xi)]


def _structure_guess(run: Run) -> tuple[float, float]:
    """The declared fixed-base frequency and damping of the run's structure."""
    spec = run.specimen()
    if isinstance(spec, SDOFSpecimen):
        return spec.frequency, spec.damping
    if isinstance(spec, ShearBuilding):
        xi_1 = float(modal_damping(spec)[0])  # the first mode's ratio
        if spec.frequencies is not None:
            return min(spec.frequencies), xi_1
        k = np.asarray(spec.stiffnesses, dtype=float)  # storey stiffnesses, eq 4.5
        K = np.diag(k + np.append(k[1:], 0.0)) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
        w2 = scipy.linalg.eigh(K, np.diag(spec.masses), eigvals_only=True)
        return float(np.sqrt(w2.min()) / TWO_PI), xi_1
    raise VtableError(f"{run.name}: Table 3.1 needs a structure (sdof or shear_building)")


def _command(run: Run) -> np.ndarray | None:
    """The command x_c when it is recorded and not zero/constant."""
    return run.channels["h_span"] if channels.usable(run, "h_span") else None


def fixed_base(run: Run, nperseg: int | None = None) -> ModalEstimate:
    """H_f = x_s/x_eff (eqs 3.11, 5.1) by a complex single-mode fit, ẍ_s/ẍ_eff being the
    same ratio. With the command recorded the estimate is referenced to it
    (`transfer_function_via`): x_eff has its notch at the fixed-base frequency (§8.6.4),
    where an H1 estimate with x_eff as input would be biased by sensor noise."""
    f0, xi0 = _structure_guess(run)
    a = accelerations(run)
    cmd = _command(run)

    def make(n: int) -> TransferFunction:
        if cmd is not None:
            return transfer_function_via(cmd, a["effective"], a["relative"], run.fs, n)
        return transfer_function(a["effective"], a["relative"], run.fs, n)

    return _estimate("fixed base", run, make, f0, xi0, 2, True, nperseg)


def rocking_coupled(run: Run, f_guess: float, xi_guess: float,
                    nperseg: int | None = None) -> ModalEstimate:
    """H_r = x_s/x_t (eq 5.2) by appendix D amplitude fitting (A³) near its peak."""
    if pitch_is_zero(run):
        raise VtableError(f"{run.name}: pitch_acc is zero throughout: no base rotation to "
                          "couple (x_t = x_eff, H_r is H_f)")
    a = accelerations(run)
    cmd = _command(run)

    def make(n: int) -> TransferFunction:
        if cmd is not None:
            return transfer_function_via(cmd, a["table"], a["relative"], run.fs, n)
        return transfer_function(a["table"], a["relative"], run.fs, n)

    return _estimate("base rotation coupling", run, make, f_guess, xi_guess, 2, False,
                     nperseg)


def fully_coupled(run: Run, f_guess: float, xi_guess: float,
                  nperseg: int | None = None,
                  name: str = "transl. and rot. coupling") -> ModalEstimate:
    """H_hr = x_s/x_c (eq 5.3), an H1 estimate with x_s = ẍ_s/(-ω²) (§3.4.1): the
    acceleration ratio over ω⁴ has the D.2 form. On a table that cannot pitch the
    coupling is translational only (`name` says so)."""
    (cmd,) = channels.require(run, "h_span", purpose="H_hr = x_s/x_c (eq 5.3)")
    a = accelerations(run)

    def make(n: int) -> TransferFunction:
        return transfer_function(cmd, a["relative"], run.fs, n)

    return _estimate(name, run, make, f_guess, xi_guess, 4, False, nperseg)


def table_3_1(run: Run, nperseg: int | None = None) -> Table31:
    """Frequencies and damping of the structure on the table from one run (the three
    rows in turn: `fixed_base`, `rocking_coupled`, `fully_coupled`; each on frames
    chosen for its mode unless `nperseg` is given). Raises VtableError when a row cannot
    be made; `vtable.ident.report` makes them one by one."""
    spec = run.specimen()
    if not isinstance(spec, SDOFSpecimen | ShearBuilding):
        raise VtableError(f"{run.name}: Table 3.1 needs a structure (sdof or shear_building)")
    fixed = fixed_base(run, nperseg)
    rocking = rocking_coupled(run, fixed.f, _xi(fixed), nperseg)
    coupled = fully_coupled(run, rocking.f, _xi(rocking), nperseg)
    return Table31(fixed, rocking, coupled)


def _xi(e: ModalEstimate) -> float:
    """A damping to choose the next row's frames from (the coupled rows are damped at
    least as much as the fixed base)."""
    return float(min(max(e.xi, 1e-3), 0.5)) if np.isfinite(e.xi) else 0.02


# ---- rocking impedance, eqs 5.8-5.11 -------------------------------------------------------
GROUPS = {"vertical": tuple(f"v{i}_force" for i in V_POS),
          "stabilizer": tuple(f"p{i}_stab" for i in P_POS)}


def pitch_moment(run: Run, groups: tuple[str, ...] = ("vertical", "stabilizer")) -> np.ndarray:
    """M = Σ x_i F_i (N m): the moment of the vertical actuators and/or stabilizers about
    the pitch axis, positive when it resists a positive θ (eq 5.8). A group whose forces
    are all zero (a table without stabilizers) is a one-line error."""
    M = np.zeros(len(run.time))
    for g in groups:
        forces = [run.channel(c) for c in GROUPS[g]]
        if not any(np.any(F) for F in forces):
            raise VtableError(f"{run.name}: {GROUPS[g][0]}..{GROUPS[g][-1]} are zero "
                              f"throughout: no {g} forces to take a moment from")
        pos = V_POS if g == "vertical" else P_POS
        for (x, _), F in zip(pos.values(), forces, strict=True):
            M += x * IN * F
    return M


def pitch_channel(run: Run) -> str:
    """The channel θ is read from: pitch_disp when usable, else pitch_acc; a one-line
    error saying why neither can be used (absent, incomplete, zero, constant)."""
    for c in ("pitch_disp", "pitch_acc"):
        if channels.usable(run, c):
            return c
    why = "; ".join(channels.channel_problem(run, c) or "" for c in ("pitch_disp", "pitch_acc"))
    raise VtableError(f"{run.name}: {why}: no measured pitch θ")


def rocking_impedance(run: Run, nperseg: int | None = None,
                      groups: tuple[str, ...] = ("vertical", "stabilizer")) -> TransferFunction:
    """G_r(ω) = M/θ (eq 5.9): real part k_r(ω) (5.10), imaginary ω c_r(ω) (5.11).

    θ is pitch_disp when recorded, else pitch_acc/(-ω²) (§3.4.1). G_r is a smooth
    impedance, so the frame is chosen for averages: 15 at 50 % overlap."""
    n = nperseg or default_frame(run)
    M = pitch_moment(run, groups)
    c = pitch_channel(run)
    if c == "pitch_disp":
        return transfer_function(run.channels[c], M, run.fs, n)
    tf = transfer_function(run.channels[c], M, run.fs, n)
    w = TWO_PI * tf.f
    with np.errstate(divide="ignore", invalid="ignore"):
        return TransferFunction(tf.f, -tf.H * w**2, tf.coherence, tf.averages)


def rocking_springs(tf: TransferFunction, f_hz: float) -> tuple[float, float]:
    """k_r and c_r at one frequency (eqs 5.10-5.11)."""
    G = tf.at(f_hz)
    return float(G.real), float(G.imag / (TWO_PI * f_hz))


def rocking_springs_fit(tf: TransferFunction, f_hz: float, what: str = "G_r") -> Fit:
    """k_r, c_r at f_hz (eqs 5.10-5.11) as a `Fit` whose standard errors are the H1
    random error ε|G_r|, ε = √(1 - γ²)/(|γ|√(2 n_d)) (Bendat & Piersol), so that low
    coherence and few averages are flagged like any fit."""
    if not tf.f[0] <= f_hz <= tf.f[-1] or not f_hz > 0:
        raise VtableError(f"{what}: {f_hz:g} Hz is outside the estimate")
    k, c = rocking_springs(tf, f_hz)
    g2 = float(np.clip(np.interp(f_hz, tf.f, tf.coherence), 0.0, 1.0))
    eps = np.sqrt(1 - g2) / (np.sqrt(g2) * np.sqrt(2 * tf.averages)) if g2 > 0 else np.inf
    G = abs(tf.at(f_hz))
    fit = Fit({"k_r": k, "c_r": c}, {"k_r": float(eps * G), "c_r": float(eps * G /
                                                                       (TWO_PI * f_hz))},
              float("nan"), float("nan"), 1, f"{what} = M/θ at {f_hz:.3f} Hz (eqs 5.9-5.11)")
    return fit.checked(resolution_hz=None, averages=tf.averages, coherence=g2)


# ---- time domain: hysteresis loops, eqs 5.12-5.14 -------------------------------------------
@dataclass(frozen=True)
class HysteresisLoop:
    """Regression stiffness and the loop measures of Fig 5.7; `fit` is the regression
    F = k x + c ẋ + F₀ (standard errors, R²), `crest_factor` max|x - x̄|/rms(x - x̄) of
    the motion (√2 for the steady sine the loop measures assume)."""

    stiffness: float  # slope of the regression line
    damping_coefficient: float  # C of eq 5.13
    damping_ratio: float  # ξ_v of eq 5.12
    dissipated: float  # W_D per cycle
    strain_energy: float  # W_s
    fit: Fit | None = None
    crest_factor: float = float("nan")


def hysteresis(x: np.ndarray, force: np.ndarray, dt: float, f_hz: float) -> HysteresisLoop:
    """Force-displacement (or moment-rotation) loop measures: k from the regression of F
    on x and ẋ, W_D the loop area per cycle (∮F dx over the record / cycles at f_hz),
    W_s = k x_max²/2, ξ_v = W_D/(4π W_s) (5.12), C = W_D/(π ω x_max²) (5.13).
    A constant x (no motion) or f_hz <= 0 is a one-line error."""
    x, force = np.asarray(x, dtype=float), np.asarray(force, dtype=float)
    if not np.ptp(x) > 0:
        raise VtableError("hysteresis: the displacement is constant (no loop)")
    if not f_hz > 0:
        raise VtableError(f"hysteresis: needs a positive loop frequency, got {f_hz:g} Hz")
    v = np.gradient(x, dt)
    A = np.column_stack([x, v, np.ones_like(x)])
    sol, *_ = np.linalg.lstsq(A, force, rcond=None)
    k, c_reg = float(sol[0]), float(sol[1])
    resid = A @ sol - force
    ss = float(resid @ resid)
    tot = float(np.sum((force - force.mean()) ** 2)) or 1.0
    cov = np.linalg.pinv(A.T @ A) * ss / max(len(x) - 3, 1)
    reg = Fit({"k": k, "c": c_reg}, {"k": float(np.sqrt(cov[0, 0])),
                                     "c": float(np.sqrt(cov[1, 1]))},
              1 - ss / tot, float(np.sqrt(ss / len(x)) / (np.sqrt(np.mean(force**2)) or 1.0)),
              len(x), "regression F = k x + c ẋ + F₀").checked()
    cycles = (len(x) - 1) * dt * f_hz
    area = float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(x)))
    wd = abs(area) / max(cycles, 1e-12)
    xc = x - x.mean()
    xmax = float(np.max(np.abs(xc)))
    ws = 0.5 * k * xmax**2
    return HysteresisLoop(k, wd / (np.pi * TWO_PI * f_hz * xmax**2),
                      wd / (4 * np.pi * ws) if ws else float("nan"), wd, ws, reg,
                      xmax / float(np.sqrt(np.mean(xc**2))))


def rocking_stiffness_from_actuators(run: Run) -> float:
    """k_r = Σ k_vi d_vi² + k_pi d_pi² (eq 5.14), each actuator's k from the regression
    of its force on its displacement (v*_disp; stabilizers from the slab's pitch)."""
    kv, dv, kp, dp = [], [], [], []
    th = run.channel("pitch_disp")
    for i, (x, _) in V_POS.items():
        d = run.channel(f"v{i}_disp")
        kv.append(-np.polyfit(d, run.channel(f"v{i}_force"), 1)[0])
        dv.append(x * IN)
    for i, (x, _) in P_POS.items():
        d = -x * IN * th  # a stabilizer at x moves -x θ
        kp.append(-np.polyfit(d, run.channel(f"p{i}_stab"), 1)[0])
        dp.append(x * IN)
    return closed_forms.rocking_stiffness_from_actuators(kv, dv, kp, dp)
