"""specimen_degradation: the specimen's stiffness falls during a run with the energy it
dissipates (ch. 3, §5.3's amplitude-dependent fixed-base parameters, as damage that
accumulates rather than a response that recovers).

Each storey i keeps its elastic spring k_i and loses part of it as its dissipated energy
E_i grows, by the stiffness-degradation law of Baber & Noori (1985), whose degradation
function grows linearly with the dissipated energy:

    k_i(t) = k_i / (1 + δ ε_i(t)ⁿ),   ε_i = E_i / E_ref,i,   Ė_i = c_i ḋ_i²,

with ḋ_i the storey's drift velocity, c_i its viscous coefficient (a SDOF frame's
c_s = 2ξωm; for a building, whose damping is modal, the measure 2ξ₁k_i/ω₁: the storey's
share of its first mode's damping were it stiffness-proportional — E_i measures what the
storey dissipates, it is not the model's exact dissipation under Rayleigh or per-mode
damping), and E_ref,i = ½ k_i (h_i/100)² its elastic energy at a 1 % drift ratio (h_i
the storey's height as the run declares it: a SDOF frame's mass height, a building's
floor-to-floor height, the first above the actuator line), so that δ is the stiffness
fraction lost per such unit of energy, and n (1 in Baber & Noori's law) lets the loss
slow down (n < 1) or speed up as the damage accumulates. The law is causal: the
stiffness at t depends only on the run up to t, so a fit on a run's first 60 % predicts
its end. The storey force it adds to the elastic −k_i d is +k_i w/(1 + w) d with
w = δ εⁿ, the state ε (dimensionless), ε̇ = c_i ḋ²/E_ref,i. Every run starts from the
specimen as the model holds it (a run of another state declares it: [specimen] state).

A bare table or a rigid block has no storey: where an effect stood a structure on the
platen in an undeclared specimen's place (`Assembly.add_structure`: platen_resonator), its
spring degrades the same way, its unit of energy that at 10 mm of deformation
(`UNDECLARED_HEIGHT`). Where no run's x_t/x_c notch (the specimen's
fixed-base frequency) moves within the run (`vtable.diagnose.stationarity`) and the
time-invariant model's residual, as a transfer function from the command, is the same in
a run's two halves (`vtable.diagnose.screen.residual_change`), the runs show no change to
fit, and the effect is not tried.
"""

from __future__ import annotations

import math

import numpy as np

from vtable.analytic.hysteresis import storey_coordinate
from vtable.analytic.structure import specimen_frequencies, storey_masses, storey_stiffnesses_of
from vtable.effects.base import Effect, Param
from vtable.errors import VtableError
from vtable.params.specimen import SDOFSpecimen, ShearBuilding

#: the drift ratio whose elastic energy is the unit of dissipated energy
REFERENCE_DRIFT = 0.01
#: the height (m) a structure without one stands for (`Assembly.structures`: a resonator an
#: effect stood on the platen in an undeclared specimen's place): its unit of energy is its
#: elastic energy at 10 mm of deformation
UNDECLARED_HEIGHT = 1.0


def degrading_storey(d: float, v: float, z, p, dz) -> float:
    """The force the degradation adds to a storey of drift d, drift velocity v (on top of
    its elastic −k d): +k w/(1 + w) d with w = δ εⁿ, so that the storey resists with
    k/(1 + w) d; the state ε grows as ε̇ = r v² (p: k N/m, r = c/E_ref in s/m², delta,
    n)."""
    e = z[0]
    dz[0] = p.r * v * v
    w = p.delta * e ** p.n if e > 0.0 else 0.0
    return p.k * w / (1.0 + w) * d


def storeys(spec) -> list[tuple[float, float, float, float]]:
    """Each storey's (stiffness N/m, mass kg, viscous coefficient N·s/m, height m) from the
    bottom; none for a bare table or a block."""
    ks, ms = storey_stiffnesses_of(spec), storey_masses(spec)
    if isinstance(spec, SDOFSpecimen):
        return [(ks[0], ms[0], spec.damping_coefficient, spec.height)]
    if isinstance(spec, ShearBuilding):
        w = 2 * math.pi * np.asarray(specimen_frequencies(spec), dtype=float)
        w1, xi1 = float(w[0]), float(spec.damping_ratios(w)[0])
        h = np.diff(np.concatenate([[0.0], np.asarray(spec.heights, dtype=float)]))
        return [(k, m, 2 * xi1 * k / w1, float(hi)) for k, m, hi in zip(ks, ms, h, strict=True)]
    return []


class SpecimenDegradation(Effect):
    name = "specimen_degradation"
    physics = ("the specimen's stiffness falls during a run with the energy it dissipates: "
               "k/(1 + δεⁿ), ε its dissipated energy per unit of elastic energy at 1 % drift")
    section = "ch. 3, §5.3 (amplitude-dependent fixed-base parameters)"
    signature = ("x_t/x_c's notch (the fixed-base frequency) moves down between the start and "
                 "the end of a run; the structure's resonance drifts lower as the run goes on")
    params = (Param("delta", "1", 0.03, 1e-5, 3.0, log=True, spread=30.0,
                    source="assumed (Baber & Noori 1985: a degradation linear in the energy; "
                           "it varies over decades between specimens)",
                    doc="δ, the stiffness fraction lost per unit of dissipated energy (the "
                        "storey's elastic energy at a 1 % drift ratio)"),
              Param("exponent", "1", 1.0, 0.2, 2.0,
                    source="Baber & Noori 1985 (1: linear in the energy)",
                    doc="n: below 1 the loss slows as the damage accumulates"))
    accumulates = True  # the loss grows with the run: fitted on its whole first 60 %

    def unsupported(self, campaign):
        """Not tried where no run's x_t/x_c notch moves within the run
        (`Campaign.notches`) and the time-invariant model's residual does not change
        between a run's halves (`Campaign.residual_change`, asked where that model leaves
        more than the noise explains): the runs show no change of the specimen to fit. A
        softening too small for the notch's resolution (a short run, a low-amplitude one)
        still changes the residual."""
        change = getattr(campaign, "residual_change", None)
        if getattr(campaign, "notches", None) or (change is not None and change.present):
            return None
        return ("no run's x_t/x_c notch (the specimen's fixed-base frequency) moves within "
                "the run" + (f", and {change.text()}" if change is not None else "") +
                ": the runs show no change of the specimen")

    def apply(self, m, p):
        spec = m.specimen
        springs = [(storey_coordinate(spec, i), None, k, mass, c, h)
                   for i, (k, mass, c, h) in enumerate(storeys(spec), start=1)]
        # else the structure an effect stood on the platen in the specimen's place
        springs = springs or [(name, "x", k, mass, c, UNDECLARED_HEIGHT)
                              for name, mass, k, c in m.structures]
        if not springs:
            raise VtableError("specimen_degradation: the specimen has no storeys to degrade "
                              f"({type(spec).__name__}) and no structure stands on the platen")
        for i, (a, b, k, mass, c, h) in enumerate(springs, start=1):
            if not h > 0:
                raise VtableError(f"specimen_degradation: storey {i} has no height (its "
                                  "unit of energy is its elastic energy at a 1 % drift ratio)")
            e_ref = 0.5 * k * (REFERENCE_DRIFT * h) ** 2
            m.add_force(degrading_storey, a, b,
                        {"k": k, "r": c / e_ref, "delta": p["delta"], "n": p["exponent"]},
                        states=1, mass=mass, stiffness=k)


EFFECT = SpecimenDegradation()
