"""The structure on the table (report §3.3, §4.2, §5.3-5.6): effective base motion,
fixed-base / rocking-coupled / coupled frequency and damping (Table 3.1), the rocking
impedance G_r = M/θ from the actuator forces, hysteresis loops, springs."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vtable import units
from vtable.analytic import closed_forms
from vtable.errors import VtableError
from vtable.ident.fits import Fit, amplitude_fit, circle_fit, fit_mode
from vtable.ident.tf import TransferFunction, transfer_function, transfer_function_via
from vtable.params.specimen import RigidBlock, SDOFSpecimen, ShearBuilding
from vtable.runs.model import Run

TWO_PI = 2 * np.pi
IN = units.to_si(1.0, "in")
#: actuator positions of the run format (x, y in inches from the table centre)
V_POS = {1: (72, 72), 2: (-72, 72), 3: (-72, -72), 4: (72, -72)}
P_POS = {1: (102, 102), 2: (-102, 102), 3: (-102, -102), 4: (102, -102)}


def effective_height(run: Run) -> float:
    """h of x_eff = x_t + hθ: the SDOF top mass (eq 3.5), a rigid block's centre of
    gravity, or a shear building's first-mode effective height (eq 4.24)."""
    spec = run.specimen()
    if isinstance(spec, SDOFSpecimen | RigidBlock):
        return spec.height
    if isinstance(spec, ShearBuilding):
        return closed_forms.effective_height_first_mode(spec.masses, spec.heights)
    raise VtableError(f"{run.name}: a bare table has no effective height")


def accelerations(run: Run) -> dict[str, np.ndarray]:
    """Table, effective (eq 4.11/4.13) and top-mass accelerations (m/s²)."""
    h = effective_height(run)
    a_t = run.channel("avg_hacc")
    a_th = run.channel("pitch_acc")
    tops = [run.channel(c) for c in ("acc_n_ne", "acc_n_nw") if run.has(c)]
    if not tops:
        raise VtableError(f"{run.name}: no top-mass accelerometer (acc_n_ne or acc_n_nw)")
    a_top = np.mean(tops, axis=0)
    a_eff = a_t + h * a_th
    return {"table": a_t, "pitch": a_th, "effective": a_eff, "top": a_top,
            "relative": a_top - a_eff}


def default_frame(run: Run, averages: int = 15, longest: int = 16384) -> int:
    """The longest power-of-two frame giving at least `averages` averages at 50 %
    overlap (the report used 2048 points and 40 averages, §3.2)."""
    n = len(run.time)
    k = 2 ** int(np.floor(np.log2(max(2 * n / (averages + 1), 64))))
    return int(min(k, longest))


@dataclass(frozen=True)
class ModalEstimate:
    """One frequency/damping estimate from a transfer function: the primary fit and the
    other methods for comparison (appendix D amplitude fit, circle fit)."""

    name: str
    tf: TransferFunction
    primary: Fit
    amplitude: Fit
    circle: Fit | None

    @property
    def f(self) -> float:
        return self.primary.params["f_n"]

    @property
    def xi(self) -> float:
        return self.primary.params["xi_n"]


def _modal(name: str, tf: TransferFunction, f_guess: float, power: int,
           complex_fit: bool) -> ModalEstimate:
    """Fit the mode near f_guess; |H|/ω^power has appendix D's form (eq D.2)."""
    w = TWO_PI * tf.f
    with np.errstate(divide="ignore", invalid="ignore"):
        R = np.where(tf.f > 0, tf.H / w**power, np.nan)
    mag = np.abs(R)
    near = (tf.f > 0.6 * f_guess) & (tf.f < 1.5 * f_guess) & np.isfinite(mag)
    if not near.any():
        raise VtableError(f"{name}: no data near {f_guess:.3g} Hz")
    fp = float(tf.f[near][np.nanargmax(mag[near])])
    amp = amplitude_fit(tf.f, mag, "A3", band=(0.75 * fp, 1.25 * fp))
    fa = amp.params["f_n"]
    try:
        circ = circle_fit(tf.f, R, (fa * 0.9, fa * 1.1))
    except VtableError:
        circ = None
    primary = amp
    if complex_fit:
        primary = fit_mode(tf.f, R, (0.85 * fa, 1.15 * fa), tf.coherence, power=0)
    return ModalEstimate(name, tf, primary, amp, circ)


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


def table_3_1(run: Run, nperseg: int | None = None) -> Table31:
    """Frequencies and damping of the structure on the table from one run.

    H_f = x_s/x_eff and H_r = x_s/x_t are formed from accelerations (ẍ_s/ẍ_eff and
    ẍ_s/ẍ_t, the same ratios); H_hr = x_s/x_c uses x_s = ẍ_s/(-ω²) (§3.4.1). Each is
    fitted by appendix D amplitude fitting (|H|/ω² has the D.2 form) near its peak.
    With the command recorded, H_f and H_r are referenced to it (`transfer_function_via`):
    x_eff has its notch at the fixed-base frequency (§8.6.4), where an H1 estimate with
    x_eff as input would be biased by sensor noise.
    """
    spec = run.specimen()
    if not isinstance(spec, SDOFSpecimen | ShearBuilding):
        raise VtableError(f"{run.name}: Table 3.1 needs a structure (sdof or shear_building)")
    a = accelerations(run)
    # H_hr is an H1 estimate: long frames keep its leakage small; the command-referenced
    # ratios H_f and H_r cancel most leakage and gain more from averaging
    n = nperseg or default_frame(run, 15)
    n_ratio = nperseg or default_frame(run, 31)
    fs = run.fs
    f0 = spec.frequency if isinstance(spec, SDOFSpecimen) else min(spec.frequencies or [2.0])
    cmd = run.channel("h_span") if run.has("h_span") and not run.missing.get("h_span") \
        else None
    if cmd is not None and np.any(cmd):
        h_f = transfer_function_via(cmd, a["effective"], a["relative"], fs, n_ratio)
        h_r = transfer_function_via(cmd, a["table"], a["relative"], fs, n_ratio)
    else:
        h_f = transfer_function(a["effective"], a["relative"], fs, n)
        h_r = transfer_function(a["table"], a["relative"], fs, n)
    h_hr = transfer_function(run.channel("h_span"), a["relative"], fs, n)
    # H_f (eq 3.11) is exactly a single mode: complex curve fit (weighted by coherence);
    # H_r and H_hr carry the table's dynamics too: appendix D amplitude fit (A³)
    fixed = _modal("fixed base", h_f, f0, 2, complex_fit=True)
    rocking = _modal("base rotation coupling", h_r, fixed.f, 2, complex_fit=False)
    # x_s/x_c = -ẍ_s/(ω² x_c): the acceleration ratio over ω⁴ has the D.2 form
    coupled = _modal("transl. and rot. coupling", h_hr, rocking.f, 4, complex_fit=False)
    return Table31(fixed, rocking, coupled)


# ---- rocking impedance, eqs 5.8-5.11 -------------------------------------------------------
def pitch_moment(run: Run, groups: tuple[str, ...] = ("vertical", "stabilizer")) -> np.ndarray:
    """M = Σ x_i F_i (N m): the moment of the vertical actuators and/or stabilizers about
    the pitch axis, positive when it resists a positive θ (eq 5.8)."""
    M = np.zeros(len(run.time))
    if "vertical" in groups:
        for i, (x, _) in V_POS.items():
            M += x * IN * run.channel(f"v{i}_force")
    if "stabilizer" in groups:
        for i, (x, _) in P_POS.items():
            M += x * IN * run.channel(f"p{i}_stab")
    return M


def rocking_impedance(run: Run, nperseg: int | None = None,
                      groups: tuple[str, ...] = ("vertical", "stabilizer")) -> TransferFunction:
    """G_r(ω) = M/θ (eq 5.9): real part k_r(ω) (5.10), imaginary ω c_r(ω) (5.11).

    θ is pitch_disp when recorded, else pitch_acc/(-ω²) (§3.4.1)."""
    n = nperseg or default_frame(run)
    M = pitch_moment(run, groups)
    if run.has("pitch_disp") and not run.missing.get("pitch_disp"):
        return transfer_function(run.channel("pitch_disp"), M, run.fs, n)
    tf = transfer_function(run.channel("pitch_acc"), M, run.fs, n)
    w = TWO_PI * tf.f
    with np.errstate(divide="ignore", invalid="ignore"):
        return TransferFunction(tf.f, -tf.H * w**2, tf.coherence, tf.averages)


def rocking_springs(tf: TransferFunction, f_hz: float) -> tuple[float, float]:
    """k_r and c_r at one frequency (eqs 5.10-5.11)."""
    G = tf.at(f_hz)
    return float(G.real), float(G.imag / (TWO_PI * f_hz))


# ---- time domain: hysteresis loops, eqs 5.12-5.14 -------------------------------------------
@dataclass(frozen=True)
class Hysteresis:
    """Regression stiffness and the loop measures of Fig 5.7."""

    stiffness: float  # slope of the regression line
    damping_coefficient: float  # C of eq 5.13
    damping_ratio: float  # ξ_v of eq 5.12
    dissipated: float  # W_D per cycle
    strain_energy: float  # W_s


def hysteresis(x: np.ndarray, force: np.ndarray, dt: float, f_hz: float) -> Hysteresis:
    """Force-displacement (or moment-rotation) loop measures: k from the regression of F
    on x and ẋ, W_D the loop area per cycle (∮F dx over the record / cycles at f_hz),
    W_s = k x_max²/2, ξ_v = W_D/(4π W_s) (5.12), C = W_D/(π ω x_max²) (5.13)."""
    x, force = np.asarray(x, dtype=float), np.asarray(force, dtype=float)
    v = np.gradient(x, dt)
    A = np.column_stack([x, v, np.ones_like(x)])
    (k, _c, _), *_ = np.linalg.lstsq(A, force, rcond=None)
    cycles = (len(x) - 1) * dt * f_hz
    area = float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(x)))
    wd = abs(area) / max(cycles, 1e-12)
    xmax = float(np.max(np.abs(x - x.mean())))
    ws = 0.5 * k * xmax**2
    return Hysteresis(float(k), wd / (np.pi * TWO_PI * f_hz * xmax**2),
                      wd / (4 * np.pi * ws) if ws else float("nan"), wd, ws)


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
