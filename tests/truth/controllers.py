"""The horizontal controller as a lab declares it: `three_variable`, `pid`, `tvc`.

One law in volts (the interchange format's `[table.controller]`, written out here again
from the servo-control literature, not from vtable), e = x_r - x_m the displacement error
(m), x_m the feedback transducer, x_r the reference:

    V = k_d [p e_n + i ∫e_n dt + d D(s) e_n] + k_d [T_v ẋ_r + T_a ẍ_r]
        - k_v ẋ_m - k_a ẍ_t - k_dp ΔP_fb,            flow = K_q V (through the valve lag)

- e_n is e through the notches placed `on = "error"`; notches `on = "drive"` act on V.
  A notch is the standard second-order band-stop
  N(s) = (s² + 2 ζ_z ω_n s + ω_n²)/(s² + 2 ζ_p ω_n s + ω_n²), with ζ_p = width/(2 f_n)
  (the -3 dB bandwidth of the full notch, in Hz) and ζ_z = ζ_p 10^(-depth/20) (depth in dB
  at f_n).
- D(s) = s/(τ_f s + 1): the derivative through a first-order filter (τ_f = 0: ideal s).
- The reference generator (tvc) is the second-order filter
  x_r/x_c = ω_g²/(s² + 2 ζ_g ω_g s + ω_g²), whose states give ẋ_r and ẍ_r for the
  feedforward; without it x_r = x_c and ẋ_c, ẍ_c come from the command itself.
- k_dp ΔP is ΔP stabilisation (pressure feedback); ΔP_fb is ΔP or its RC high-pass (eq B.4)
  when the effect force_feedback_filter is on.

`three_variable` with these physical gains is the report's loop of eqs 6.1-6.4 in volts
(displacement, velocity and ΔP feedback): K_q k_d p = k_t and K_q k_dp = k_t k_p.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .errors import TruthError

KINDS = ("three_variable", "pid", "tvc")
NOTCH_PLACES = ("error", "drive")
MAX_NOTCHES = 2


@dataclass(frozen=True)
class Notch:
    """A second-order notch: centre `frequency_hz`, -3 dB `width_hz`, `depth_db` at the
    centre, on the displacement error or on the drive."""

    frequency_hz: float
    width_hz: float
    depth_db: float = 40.0
    on: str = "error"

    @property
    def zetas(self) -> tuple[float, float]:
        """(ζ_z, ζ_p) of N(s) = (s² + 2ζ_z ω s + ω²)/(s² + 2ζ_p ω s + ω²)."""
        zp = self.width_hz / (2 * self.frequency_hz)
        return zp * 10 ** (-self.depth_db / 20), zp

    def declared(self) -> dict:
        return {"frequency_hz": self.frequency_hz, "width_hz": self.width_hz,
                "depth_db": self.depth_db, "on": self.on}


@dataclass(frozen=True)
class Controller:
    """A declared horizontal controller (SI gains; see the module docstring for the law)."""

    kind: str
    displacement_gain: float  # k_d, V/m
    p: float = 1.0
    i: float = 0.0  # 1/s
    d: float = 0.0  # s
    derivative_filter: float = 0.0  # τ_f, s
    feedforward_velocity: float = 0.0  # T_v, s
    feedforward_acceleration: float = 0.0  # T_a, s²
    velocity_gain: float = 0.0  # k_v, V·s/m
    acceleration_gain: float = 0.0  # k_a, V·s²/m
    pressure_gain: float = 0.0  # k_dp, V/Pa
    reference: tuple[float, float] | None = None  # (f_g Hz, ζ_g) of the reference generator
    notches: tuple[Notch, ...] = field(default_factory=tuple)

    def __post_init__(self):
        if self.kind not in KINDS:
            raise TruthError(f"controller: kind must be one of {', '.join(KINDS)}, got "
                             f"{self.kind!r}")
        if not (math.isfinite(self.displacement_gain) and self.displacement_gain > 0):
            raise TruthError("controller: displacement_gain (V/m) must be > 0")
        for k in ("p", "i", "d", "derivative_filter", "feedforward_velocity",
                  "feedforward_acceleration", "velocity_gain", "acceleration_gain",
                  "pressure_gain"):
            v = getattr(self, k)
            if not (math.isfinite(v) and v >= 0):
                raise TruthError(f"controller: {k} must be a finite number >= 0, got {v!r}")
        if self.p == self.i == self.d == 0:
            raise TruthError("controller: at least one of p, i, d must be above zero")
        if self.reference is not None:
            f_g, z_g = self.reference
            if not (f_g > 0 and z_g > 0):
                raise TruthError(f"controller: reference (f_g, ζ_g) must be positive, got "
                                 f"{self.reference}")
        if len(self.notches) > MAX_NOTCHES:
            raise TruthError(f"controller: at most {MAX_NOTCHES} notches")
        for n in self.notches:
            if n.on not in NOTCH_PLACES or not (n.frequency_hz > 0 and n.width_hz > 0
                                                and n.depth_db >= 0):
                raise TruthError(f"controller: bad notch {n}")

    def declared(self) -> dict:
        """The run format's [table.controller] table (keys name their units); zero terms
        are left out."""
        out: dict = {"kind": self.kind, "displacement_gain_v_per_m": self.displacement_gain}
        for key, v in (("p", self.p), ("i_per_s", self.i), ("d_s", self.d),
                       ("derivative_filter_s", self.derivative_filter),
                       ("feedforward_velocity_s", self.feedforward_velocity),
                       ("feedforward_acceleration_s2", self.feedforward_acceleration),
                       ("velocity_gain_v_s_per_m", self.velocity_gain),
                       ("acceleration_gain_v_s2_per_m", self.acceleration_gain),
                       ("pressure_gain_v_per_pa", self.pressure_gain)):
            if v != 0 or key == "p":
                out[key] = float(v)
        if self.reference is not None:
            out["reference_frequency_hz"] = float(self.reference[0])
            out["reference_damping"] = float(self.reference[1])
        if self.notches:
            out["notch"] = [n.declared() for n in self.notches]
        return out


def three_variable(displacement_gain: float, p: float = 1.0, velocity_gain: float = 0.0,
                   pressure_gain: float = 0.0, notches: tuple[Notch, ...] = ()) -> Controller:
    """The report's three-variable loop (eqs 6.1-6.4) with physical gains: P on the
    displacement error, velocity and ΔP feedback."""
    return Controller("three_variable", displacement_gain, p=p, velocity_gain=velocity_gain,
                      pressure_gain=pressure_gain, notches=tuple(notches))


def pid(displacement_gain: float, p: float = 1.0, i: float = 0.0, d: float = 0.0,
        derivative_filter: float = 0.0, feedforward_velocity: float = 0.0,
        feedforward_acceleration: float = 0.0, pressure_gain: float = 0.0,
        notches: tuple[Notch, ...] = ()) -> Controller:
    """PID on the displacement error (derivative through a first-order filter τ_f), with
    optional velocity (T_v) and acceleration (T_a) feedforward, ΔP stabilisation and
    notches."""
    return Controller("pid", displacement_gain, p=p, i=i, d=d,
                      derivative_filter=derivative_filter,
                      feedforward_velocity=feedforward_velocity,
                      feedforward_acceleration=feedforward_acceleration,
                      pressure_gain=pressure_gain, notches=tuple(notches))


def tvc(displacement_gain: float, p: float = 1.0, velocity_gain: float = 0.0,
        acceleration_gain: float = 0.0, feedforward_velocity: float = 0.0,
        feedforward_acceleration: float = 0.0, reference: tuple[float, float] | None = None,
        pressure_gain: float = 0.0, notches: tuple[Notch, ...] = ()) -> Controller:
    """Three-variable control as digital controllers do it: displacement, velocity and
    acceleration feedback, feedforward of the reference velocity and acceleration made by
    a second-order reference generator from the displacement command."""
    return Controller("tvc", displacement_gain, p=p, velocity_gain=velocity_gain,
                      acceleration_gain=acceleration_gain,
                      feedforward_velocity=feedforward_velocity,
                      feedforward_acceleration=feedforward_acceleration, reference=reference,
                      pressure_gain=pressure_gain, notches=tuple(notches))
