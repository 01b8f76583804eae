"""The digital controller's terms as one control stage: integral and filtered derivative
of the displacement error, velocity and acceleration feedforward, acceleration feedback,
a reference generator and up to two notch filters — the law of the run format's ``pid``
and ``tvc`` kinds (docs/run-format.md):

    u = k_d [p e + i ∫e dt + d D(s) e] + k_d [T_v ẋ_r + T_a ẍ_r] - k_v ẋ_t - k_a ẍ_t
        - k_dp ΔP

with e = x_r - x_t through the notches placed on the error, u through those placed on
the drive. The element's P law (eqs 6.1-6.4) already holds k_d p e, k_v ẋ_t and k_dp ΔP
(`vtable.runs.lab`); this stage adds the rest per unit of k_d p.

- x_r: the reference generator x_r/x_c = ω_g²/(s² + 2ζ_g ω_g s + ω_g²) when declared (e is
  then x_r - x_t). Otherwise x_r = x_c, and the feedforward reads the command's
  derivatives through L(s) = (1 + 3τ_c s)/(τ_c s + 1)³ (τ_c = `COMMAND_FILTER`): a lag
  whose first-order error the lead cancels, so s L and s² L are proper and within
  3(ωτ_c)² of s and s² (0.7 % at 30 Hz).
- D(s) = s/(τ_f s + 1); τ_f = 0 takes e's derivative as ẋ_r - ẋ_t.
- ẍ_t: the feedback velocity's derivative through (1 + 2τ_a s)/(τ_a s + 1)² (τ_a =
  `ACCELERATION_FILTER`; the element carries the platen's velocity, not its
  acceleration): within (ωτ_a)² of s (0.2 % at 30 Hz).
- a notch N(s) = (s² + 2ζ_z ω s + ω²)/(s² + 2ζ_p ω s + ω²), ζ_p = width/(2 f),
  ζ_z = ζ_p 10^(-depth/20).

States: ∫e, the derivative filter, the acceleration filter (2), the reference (3: the
generator's x_r and ẋ_r, or L's chain), two per notch.
"""

from __future__ import annotations

import math

from vtable._numba import njit
from vtable.errors import VtableError
from vtable.hydraulics.stage import Stage

#: s: τ_c of the filter vtable reads a command's derivatives through when no reference
#: generator is declared (see the module docstring)
COMMAND_FILTER = 0.25e-3
#: s: τ_a of the filter vtable reads the platen's acceleration through
ACCELERATION_FILTER = 0.25e-3
IDLE = 1.0  # rad/s: the rate of a filter whose output nothing reads (steady, not stiff)

PARAMS = ("i", "d", "tau_d", "t_v", "t_a", "k_a", "tau_a", "w_r", "z_r", "ref",
          "n1_w", "n1_zz", "n1_zp", "n1_err", "n2_w", "n2_zz", "n2_zp", "n2_err")


@njit(cache=True)
def _notch(x, a, b, w, zz, zp, da):
    """One notch on x (states a, b; rates into da[0], da[1]); returns N(s) x."""
    da[0] = b
    da[1] = x - w * w * a - 2.0 * zp * w * b
    return x + 2.0 * (zz - zp) * w * b


def digital_law(u, xc, x, v, z, p, dz):
    """The stage's law (see the module docstring): the P law's drive u per unit gain in,
    the drive with the digital terms out."""
    if p.ref > 0.5:  # the declared reference generator: x_r, ẋ_r
        a_r = p.w_r * p.w_r * (xc - z[3]) - 2.0 * p.z_r * p.w_r * z[4]
        dz[3] = z[4]
        dz[4] = a_r
        dz[5] = -z[5]
        x_r, v_r = z[3], z[4]
    else:  # L(s)'s chain w1, w2, w3 at rate c = 1/τ_c: x_r = 3 w2 - 2 w3 feeds forward
        c = p.w_r
        d1 = c * (xc - z[3])
        d2 = c * (z[3] - z[4])
        d3 = c * (z[4] - z[5])
        dz[3] = d1
        dz[4] = d2
        dz[5] = d3
        v_r = 3.0 * d2 - 2.0 * d3
        a_r = c * (3.0 * (d1 - d2) - 2.0 * (d2 - d3))
        x_r = xc
    e = x_r - x
    e_n = e
    if p.n1_err > 0.5:
        e_n = _notch(e_n, z[6], z[7], p.n1_w, p.n1_zz, p.n1_zp, dz[6:8])
    if p.n2_err > 0.5:
        e_n = _notch(e_n, z[8], z[9], p.n2_w, p.n2_zz, p.n2_zp, dz[8:10])
    dz[0] = e_n
    if p.tau_d > 0.0:
        de = (e_n - z[1]) / p.tau_d
        dz[1] = de
    else:
        de = v_r - v
        dz[1] = -z[1]
    acc = 0.0
    if p.tau_a > 0.0:  # (1 + 2τ s)/(τ s + 1)² on v, differentiated
        a1 = (v - z[2]) / p.tau_a
        a2 = (z[2] - z[10]) / p.tau_a
        dz[2] = a1
        dz[10] = a2
        acc = 2.0 * a1 - a2
    else:
        dz[2] = -z[2]
        dz[10] = -z[10]
    u = u + (e_n - (xc - x)) + p.i * z[0] + p.d * de + p.t_v * v_r + p.t_a * a_r \
        - p.k_a * acc
    if p.n1_err <= 0.5:
        u = _notch(u, z[6], z[7], p.n1_w, p.n1_zz, p.n1_zp, dz[6:8])
    if p.n2_err <= 0.5:
        u = _notch(u, z[8], z[9], p.n2_w, p.n2_zz, p.n2_zp, dz[8:10])
    return u


DIGITAL = Stage("digital_controller", "control", digital_law, PARAMS, states=11, linear=True)


def digital_params(c) -> dict[str, float] | None:
    """The stage's parameters (per unit P gain k_d p) of a declared controller
    (`vtable.runs.table.ControllerDescription`, SI); None when it has no digital term."""
    kd, p = c.displacement_gain, c.p if c.p is not None else 1.0
    if not p > 0:
        raise VtableError("[table.controller].p: vtable's models need p > 0 (the loop's "
                          "gain is read per unit of k_d p)")
    i, d = c.i or 0.0, c.d or 0.0
    tv, ta = c.feedforward_velocity or 0.0, c.feedforward_acceleration or 0.0
    ka = c.acceleration_gain or 0.0
    notches = tuple(c.notches or ())
    ref = c.reference_frequency is not None
    if not (i or d or tv or ta or ka or notches or ref):
        return None
    tau_d = c.derivative_filter or 0.0
    uses_rate = bool(tv or ta or (d and not tau_d))
    if ref:
        w_r, z_r = 2 * math.pi * c.reference_frequency, c.reference_damping or 1.0
    elif uses_rate:
        w_r, z_r = 1.0 / COMMAND_FILTER, 1.0
    else:
        w_r, z_r = IDLE, 1.0
    out = {"i": i / p, "d": d / p, "tau_d": tau_d, "t_v": tv / p, "t_a": ta / p,
           "k_a": ka / (kd * p) if ka else 0.0, "tau_a": ACCELERATION_FILTER if ka else 0.0,
           "w_r": w_r, "z_r": z_r, "ref": 1.0 if ref else 0.0}
    for k in (1, 2):
        if k <= len(notches):
            n = notches[k - 1]
            zp = n.width / (2 * n.frequency)
            out |= {f"n{k}_w": 2 * math.pi * n.frequency, f"n{k}_zp": zp,
                    f"n{k}_zz": zp * 10 ** (-n.depth_db / 20),
                    f"n{k}_err": 1.0 if n.on == "error" else 0.0}
        else:  # an identity notch (ζ_z = ζ_p) on the drive, at a slow idle rate
            out |= {f"n{k}_w": IDLE, f"n{k}_zp": 1.0, f"n{k}_zz": 1.0, f"n{k}_err": 0.0}
    return out

