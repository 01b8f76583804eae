"""The effect catalog: named pieces of physics a model of the table can add
(shared/spec/effects.md; the names are the public vocabulary).

Each effect is defined here once: physics, parameters (report units at this edge, with
bounds and defaults), the report section and its signature in measured runs. The reduced
model (`reduced.py`) and the virtual table (`virtual.py`) both read the same parameters
through `Physics`.
"""

from __future__ import annotations

from dataclasses import dataclass

from vtable.errors import VtableError


@dataclass(frozen=True)
class EffectParam:
    name: str
    unit: str
    default: float
    lower: float
    upper: float
    log: bool = False  # fitted on a log scale
    doc: str = ""


@dataclass(frozen=True)
class Effect:
    name: str
    physics: str
    section: str
    signature: str
    params: tuple[EffectParam, ...]

    def defaults(self) -> dict[str, float]:
        return {p.name: p.default for p in self.params}

    def check(self, values: dict[str, float], where: str = "") -> dict[str, float]:
        """Fill defaults; a value outside its bounds or an unknown name is an error."""
        where = where or self.name
        known = {p.name: p for p in self.params}
        for k in values:
            if k not in known:
                raise VtableError(f"{where}: unknown parameter {k!r}; expected "
                                  f"{', '.join(known) or 'none'}")
        out = self.defaults() | dict(values)
        for k, v in out.items():
            p = known[k]
            if not p.lower <= v <= p.upper:
                raise VtableError(f"{where}: {k} = {v:g} {p.unit} is outside "
                                  f"[{p.lower:g}, {p.upper:g}]")
        return out


P = EffectParam
CATALOG: dict[str, Effect] = {e.name: e for e in (
    Effect("pitch_flexibility",
           "the table rocks about y against the vertical actuators' control loop and the "
           "passive stabilizers: a rocking spring k_θ and dashpot c_θ (hybrid model, eq 8.37)",
           "ch. 5, 8", "pitch channels driven at the coupled frequency; the x_t/x_c peak and "
           "notch move below the fixed-base frequency; structure response near f_c",
           (P("k_theta", "lb-in/rad", 2.22e10, 1e9, 1e12, True, "Table 8.1"),
            P("c_theta", "lb-in-s/rad", 3.7e8, 1e6, 1e10, True, "Table 8.1"))),
    Effect("force_feedback_filter", "an RC high-pass filter on the ΔP (force) feedback",
           "app. B (eqs B.4-B.7)", "low-frequency phase and amplitude of x_t/x_c; the loop's "
                                   "damping seems lower than the ΔP knob suggests",
           (P("rc", "s", 0.01, 1e-3, 1.0, True, "Table B.5"),)),
    Effect("valve_flow_nonlinearity",
           "turbulent orifice flow q ∝ x_sp √(P_s - sign(x_sp) P_L): the loop gain falls "
           "with load", "app. C (eq C.14)",
           "amplitude dependence: larger spans see a lower, more lagging x_t/x_c, most at "
           "high frequency where the load pressure is large",
           (P("supply_pressure", "psi", 3000.0, 300.0, 6000.0, True, "§2.2"),)),
    Effect("actuator_friction", "Coulomb friction in the actuators and bearings, F_r sign(ẋ)",
           "app. C (eq C.12)", "small spans lose more than large ones; distortion at motion "
                               "reversals; force offsets",
           (P("friction", "kip", 1.0, 0.01, 30.0, True, "total over H1-H3"),)),
    Effect("flow_saturation", "the servovalve's rated flow caps actuator velocity",
           "§2.2, app. C", "clipping when the command velocity exceeds the cap; large "
                           "spans and earthquakes only",
           (P("v_max", "in/s", 25.0, 1.0, 60.0, True, "§2.2: 25 in/s horizontal"),)),
    Effect("valve_dynamics", "the servovalve does not respond instantly: a first-order "
                             "spool (flow) lag τ", "§6.2, app. C",
           "extra phase lag growing with frequency; lower bandwidth",
           (P("tau", "s", 0.002, 1e-4, 0.05, True, "assumed"),)),
    Effect("oil_column_air", "entrained air lowers the effective bulk modulus and makes it "
                             "pressure dependent, 1/β_e = 1/β + r/(1.4 P)",
           "eq 8.5, C.10", "lower open-loop frequency f_o; a softer oil column",
           (P("air_ratio", "1", 0.01, 1e-4, 0.2, True, "eq C.10's r"),)),
    Effect("amplitude_dependent_damping",
           "the specimen's damping grows with its response amplitude (friction between the "
           "stacked masses): a quadratic damper c₂|ẋ_s|ẋ_s, ξ rising γ per inch of drift",
           "§3.3.1.2, Fig. 3.2", "structure channels: the resonance is damped more in the "
                                 "large spans than the small ones",
           (P("gamma", "1/in", 0.01, 1e-4, 0.5, True, "assumed"),)),
    Effect("foundation_compliance",
           "the reaction mass (1580 kips, §2.2) moves on a horizontal spring and dashpot, so "
           "the actuators push against a compliant base", "§1.2 (Rea)",
           "absolute accelerations differ from the actuator displacements' at low "
           "frequency; a foundation resonance",
           (P("f_f", "Hz", 10.0, 1.0, 60.0, True, "assumed"),
            P("xi_f", "1", 0.1, 0.005, 0.9, True, "assumed"))),
    Effect("sensor_filter", "the measurement chain's anti-aliasing low-pass (4-pole "
                            "Butterworth, 100 Hz, §2.3) before sampling",
           "§2.3", "every measured channel lags the command by a delay ≈ 2.6/(2π f_c); "
                   "phase error growing linearly with frequency",
           (P("cutoff_hz", "Hz", 100.0, 5.0, 400.0, True, "§2.3"),)),
)}

#: effects the servo kernel implements
SERVO_EFFECTS = ("force_feedback_filter", "valve_flow_nonlinearity", "actuator_friction",
                 "flow_saturation", "valve_dynamics", "oil_column_air")


def effect(name: str) -> Effect:
    try:
        return CATALOG[name]
    except KeyError:
        raise VtableError(f"unknown effect {name!r}; the catalog has "
                          f"{', '.join(CATALOG)}") from None
