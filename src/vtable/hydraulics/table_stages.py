"""The table's own stages of the hydraulic element, each law written once: the
servovalve's spool lag (§6.2, app. C) and the RC high-pass filter on the ΔP (force)
feedback (app. B, eq B.4).

A table that declares them has them (`table_stages`: its RC filter, a lab table's digital
controller's terms and its valves' lag); the effects `valve_dynamics` and
`force_feedback_filter` add the same laws where the declaration does not hold them
(`VALVE_LAG`: a further lag in series with a declared one)."""

from __future__ import annotations

from vtable.hydraulics.stage import Stage


def spool_lag(q, z, p, dz):
    """The valve flow z[0] lagging the commanded flow q by τ = p.tau: τ q̇_v = q − q_v."""
    dz[0] = (q - z[0]) / p.tau
    return z[0]


def filtered(P, z, p):
    """The pressure fed back: the filter's state P_f."""
    return z[0]


def filter_rate(P, dP, z, p, dz):
    """Ṗ_f = -P_f/RC + Ṗ_L (eq B.4)."""
    dz[0] = dP - z[0] / p.rc


#: a table's servovalve lag (LNEC's 24.6 ms)
SPOOL_LAG = Stage("spool_lag", "valve", spool_lag, ("tau",), states=1, linear=True,
                  state_units=("m3/s",))
#: the same law beyond a table's declared lag, in series with it (`valve_dynamics`)
VALVE_LAG = Stage("valve_lag", "valve", spool_lag, ("tau",), states=1, linear=True,
                  state_units=("m3/s",))
#: the RC filter on the ΔP feedback (the EERC table's, Table 3.2)
RC_FILTER = Stage("rc_filter", "feedback", filtered, ("rc",), states=1, state_units=("Pa",),
                  linear=True, rate=filter_rate)


def table_stages(vt, rc: bool = True) -> list:
    """The stages a table `vt` (a `VirtualTable`) declares on its horizontal group, as
    (stage, parameters): its RC filter on the ΔP feedback (eq B.4; left out when not
    `rc`: the reduced and multibody models carry it in their base loop), its
    servovalves' lag, a lab table's digital controller's terms. Every model reads them
    here."""
    out = [(RC_FILTER, {"rc": vt.horizontal_servo.rc})] if vt.horizontal_servo.rc and rc \
        else []
    out += [(SPOOL_LAG, {"tau": vt.valve_lag})] if vt.valve_lag else []
    return out + ([vt.control.use] if vt.control is not None else [])
