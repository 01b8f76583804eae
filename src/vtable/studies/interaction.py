"""Shaking table-structure interaction for one specimen: the report's five models side by
side (§9.4), their first coupled mode (§9.3) and the pseudo-velocity spectra of a record
through each (§9.9).

Every model is driven by the table command x_c and reports the structure's deformation
x_s (relative to the pitching table top). PSV is ω_s max|x_s| with the fixed-base ω_s, as
in the report (§9.1).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vtable._numba import njit
from vtable.analytic.base import LinearModel
from vtable.analytic.closed_forms import effective_height_first_mode, modal_mass
from vtable.analytic.hold import first_order_hold
from vtable.analytic.interaction import FixedBaseModel, RockingModel
from vtable.analytic.mechanical import MechanicalModel
from vtable.analytic.pitch import HybridModel
from vtable.analytic.sdof import TableSDOF
from vtable.analytic.structure import building_matrices, fixed_base_modes
from vtable.errors import VtableError
from vtable.params import (
    HorizontalSpring,
    HybridParams,
    MechanicalParams,
    OpenLoop,
    RockingSpring,
    SDOFSpecimen,
    ShearBuilding,
    Specimen,
    TableSDOFParams,
    presets,
)
from vtable.units import G

TWO_PI = 2 * np.pi
MODELS = ("fixed base", "one-directional", "rocking", "hybrid", "mechanical")


# ---- the table: one source for the EERC values ------------------------------------------
@dataclass(frozen=True)
class TableModels:
    """The table side of the five models: mass and pitch inertia (eerc.toml), the
    horizontal loop (Table 8.1/9.1), the rocking spring (Table 8.1) and the mechanical
    model's horizontal spring (Table 5.1)."""

    m_t: float
    inertia: float
    open_loop: OpenLoop
    rocking: RockingSpring
    horizontal: HorizontalSpring

    @classmethod
    def eerc(cls) -> TableModels:
        g = presets.eerc_table().geometry
        return cls(g.mass, g.pitch_inertia,
                   presets.model_part("table8_1", "open_loop", OpenLoop),
                   presets.model_part("table8_1", "rocking", RockingSpring),
                   presets.model_part("table5_1", "horizontal", HorizontalSpring))


def equivalent_sdof(spec: Specimen) -> SDOFSpecimen:
    """An SDOF specimen as is; a shear building as its first mode: f_1, modal mass
    (eqs 5.6-5.7) at the effective height h_e1 (eqs 4.22-4.24), modal damping."""
    if isinstance(spec, SDOFSpecimen):
        return spec
    if isinstance(spec, ShearBuilding):
        M, K, _ = building_matrices(spec)
        w, _ = fixed_base_modes(M, K)
        m, h = np.diag(M), np.asarray(spec.heights)
        return SDOFSpecimen(weight=modal_mass(m, h) * G, height=effective_height_first_mode(m, h),
                            frequency=float(w[0]) / TWO_PI,
                            damping=float(spec.damping_ratios(w)[0]),
                            title=f"{spec.title}: first mode at h_e1", source="§4.2.2")
    raise VtableError(f"interaction assessment needs an sdof or shear_building specimen, "
                      f"got kind {getattr(spec, 'kind', '?')!r}")


def five_models(spec: SDOFSpecimen, table: TableModels | None = None
                ) -> dict[str, LinearModel]:
    """The §9.4 models for `spec` on `table` (EERC by default), keyed by MODELS."""
    t = table or TableModels.eerc()
    hyb = HybridParams.from_physical(spec, t.m_t, t.inertia, t.open_loop, t.rocking)
    mech = MechanicalParams.from_physical(spec, t.m_t, t.inertia, t.horizontal, t.rocking)
    st = hyb.structure
    return {
        "fixed base": FixedBaseModel(st),
        "one-directional": TableSDOF(TableSDOFParams(open_loop=t.open_loop,
                                                     structure=dataclasses.replace(st, v=0.0))),
        "rocking": RockingModel(st, hyb.f_theta, hyb.xi_theta),
        "hybrid": HybridModel(hyb, height=spec.height),
        "mechanical": MechanicalModel(mech, height=spec.height),
    }


def coupled_mode(model: LinearModel) -> tuple[float, float]:
    """First coupled frequency (Hz) and damping (§9.3, eqs 9.1-9.4)."""
    m = model.modes().first
    return m.f_hz, m.damping


# ---- spectra through a model ------------------------------------------------------------
def _augmented(model: LinearModel, output: str, dt: float):
    """Φ, G0, G1 and c for the model driven by ẍ_c linear over each step (the
    Nigam-Jennings assumption), with x_c and ẋ_c appended to the state from rest:
    y_{k+1} = Φ y_k + G0 a_k + G1 a_{k+1} (`first_order_hold`)."""
    n = model.A.shape[0]
    i = model.outputs.index(output)
    m = n + 2
    A = np.zeros((m, m))
    A[:n, :n] = model.A
    A[:n, n] = model.B[:, 0]
    A[n, n + 1] = 1.0
    b = np.zeros(m)
    b[n + 1] = 1.0  # input ẍ_c
    phi, gam, lam = first_order_hold(A, b, dt)
    c = np.zeros(m)
    c[:n], c[n] = model.C[i], model.D[i, 0]
    return phi, gam - lam, lam, c


@njit(cache=True)
def _peak_outputs(acc, Phi, G0, G1, c):
    # any state size; spectra._peaks stays a 2-state unrolled copy because it is twice
    # as fast, which is what keeps response_spectrum >= 10x eqsig
    P, m = c.shape
    out = np.zeros(P)
    x = np.zeros(m)
    y = np.zeros(m)
    for p in range(P):
        x[:] = 0.0
        peak = 0.0
        for k in range(acc.shape[0] - 1):
            ak, ak1 = acc[k], acc[k + 1]
            for r in range(m):
                s = G0[p, r] * ak + G1[p, r] * ak1
                for q in range(m):
                    s += Phi[p, r, q] * x[q]
                y[r] = s
            z = 0.0
            for r in range(m):
                x[r] = y[r]
                z += c[p, r] * y[r]
            if abs(z) > peak:
                peak = abs(z)
        out[p] = peak
    return out


def peak_response(models: Sequence[LinearModel], acc: np.ndarray, dt: float,
                  output: str = "x_s") -> np.ndarray:
    """max|output| of each model under command acceleration `acc` (m/s², step dt), all
    models of one state size at a time."""
    acc = np.ascontiguousarray(acc, dtype=float)
    out = np.empty(len(models))
    sizes = np.array([mdl.A.shape[0] for mdl in models])
    for n in np.unique(sizes):
        idx = np.flatnonzero(sizes == n)
        parts = [_augmented(models[j], output, dt) for j in idx]
        Phi, G0, G1, c = (np.ascontiguousarray(np.stack(z)) for z in zip(*parts, strict=True))
        out[idx] = _peak_outputs(acc, Phi, G0, G1, c)
    return out


def psv_spectra(spec: SDOFSpecimen, acc: np.ndarray, dt: float, periods,
                table: TableModels | None = None,
                names: Sequence[str] = MODELS) -> dict[str, np.ndarray]:
    """PSV (m/s) = ω_s max|x_s| of `spec` retuned to each period, through each model."""
    periods = np.asarray(periods, dtype=float)
    per_model = {n: [] for n in names}
    for T in periods:
        ms = five_models(dataclasses.replace(spec, frequency=float(1 / T)), table)
        for n in names:
            per_model[n].append(ms[n])
    w = TWO_PI / periods
    return {n: w * peak_response(per_model[n], acc, dt) for n in names}


# ---- sweeps of the coupled mode (Figs 9.4-9.12) ------------------------------------------
def sweep(spec: SDOFSpecimen, parameter: str, values, table: TableModels | None = None,
          names: Sequence[str] = MODELS[1:]) -> dict[str, np.ndarray]:
    """First coupled frequency and damping of each model as `parameter` (frequency,
    damping, weight or height, in SI) takes `values`: {model: array (len(values), 2)}."""
    if parameter not in ("frequency", "damping", "weight", "height"):
        raise VtableError(f"sweep parameter must be frequency, damping, weight or height, "
                          f"got {parameter!r}")
    out = {n: np.empty((len(values), 2)) for n in names}
    for i, v in enumerate(values):
        ms = five_models(dataclasses.replace(spec, **{parameter: float(v)}), table)
        for n in names:
            out[n][i] = coupled_mode(ms[n])
    return out


# ---- the assessment ---------------------------------------------------------------------
@dataclass
class Assessment:
    """Coupled modes, spectra and the compensation of one specimen under one record."""

    specimen: SDOFSpecimen
    record: str
    modes: dict[str, tuple[float, float]]
    periods: np.ndarray
    psv: dict[str, np.ndarray]
    psv_at_specimen: dict[str, float]
    rocking_share: float
    elongation: float
    compensated_error: float

    def verdict(self) -> str:
        s = self.specimen
        f_s, xi_s = s.frequency, s.damping
        f_c, xi_c = self.modes["hybrid"]
        fixed = self.psv_at_specimen["fixed base"]
        lines = [f"{s.title}: {s.weight / 4448.2216:.1f} kip at {s.height / 0.0254:.0f} in, "
                 f"f_s {f_s:.2f} Hz, xi_s {100 * xi_s:.1f} %; record {self.record}",
                 f"{'model':16s} {'f_c Hz':>7s} {'T_c s':>6s} {'xi_c %':>7s} "
                 f"{'PSV at T_s':>11s} {'vs fixed':>9s}"]
        for n, (f, xi) in self.modes.items():
            v = self.psv_at_specimen[n]
            lines.append(f"{n:16s} {f:7.2f} {1 / f:6.3f} {100 * xi:7.1f} "
                         f"{v / 0.0254:8.2f} in/s {100 * (v / fixed - 1):+8.0f} %")
        d = 100 * (self.psv_at_specimen["hybrid"] / fixed - 1)
        lines.append(
            f"verdict: coupled period {1 / f_c:.2f} s vs fixed-base {1 / f_s:.2f} s; damping "
            f"{100 * xi_s:.0f} % -> {100 * xi_c:.0f} %; PSV at the specimen period {d:+.0f} %; "
            f"rocking contributes {100 * self.rocking_share:.0f} % of the shift")
        lines.append(
            f"compensation (§10.2): stretch the record's time axis by f_s/f_c = "
            f"{self.elongation:.3f} (or stiffen the specimen by {self.elongation**2:.2f}x); "
            f"the hybrid peak deformation is then {100 * self.compensated_error:+.0f} % vs "
            f"fixed-base; what remains is the damping {100 * xi_s:.0f} % -> {100 * xi_c:.0f} %, "
            f"which a record cannot compensate")
        return "\n".join(lines)


def assess(spec: Specimen, acc: np.ndarray, dt: float, record: str = "record",
           periods=None, table: TableModels | None = None) -> Assessment:
    """The §9 assessment of `spec` (SDOF, or a building through its first mode) under the
    table command acceleration `acc` (m/s², step dt)."""
    s = equivalent_sdof(spec)
    periods = np.geomspace(0.05, 3.0, 60) if periods is None else np.asarray(periods)
    ms = five_models(s, table)
    modes = {"fixed base": (s.frequency, s.damping)}
    modes.update({n: coupled_mode(ms[n]) for n in MODELS[1:]})
    peaks = peak_response([ms[n] for n in MODELS], acc, dt)
    at = dict(zip(MODELS, TWO_PI * s.frequency * peaks, strict=True))
    f_s, f_1, f_h = s.frequency, modes["one-directional"][0], modes["hybrid"][0]
    share = (f_1 - f_h) / (f_s - f_h) if abs(f_s - f_h) > 1e-9 else 0.0
    alpha = f_s / f_h
    # the command stretched in time (x_c(t/α), same displacement): ẍ scales by 1/α²
    stretched = np.interp(np.arange(0, (len(acc) - 1) * alpha + 1e-12, 1.0) / alpha,
                          np.arange(len(acc)), acc) / alpha**2
    comp = peak_response([ms["hybrid"]], stretched, dt)[0] / peaks[0] - 1
    return Assessment(s, record, modes, periods, psv_spectra(s, acc, dt, periods, table), at,
                      float(share), float(alpha), float(comp))


__all__ = ["MODELS", "Assessment", "FixedBaseModel", "RockingModel", "TableModels", "assess",
           "coupled_mode", "equivalent_sdof", "five_models", "peak_response",
           "psv_spectra", "sweep"]
