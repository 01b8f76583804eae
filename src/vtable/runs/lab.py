"""The shaking table a run was made on, as every model reads it (SI): the platen, its
horizontal actuators and their servo loop, the controller, the limits.

`lab_table(desc)` turns a run's [table] (`vtable.runs.table.TableDescription`: a preset
and/or a description, docs/run-format.md) into the one table description every model
reads (`vtable.params.virtual.VirtualTable`, `vtable.tables.lab.described_table`); a run without
[table] is the EERC table (the format's default). The horizontal loop is described per
actuator by the report's constants (`ServoConstants`, eqs 6.1-6.5): for the EERC table
Table B.5's at the Table 3.2 knobs; for a table described physically, the flow gain per
metre of displacement error k_t = (valve flow gain) x (displacement gain) x (P gain), no
ΔP or velocity feedback unless given, the leakage as k_ct, the platen's viscous damping
shared by the actuators, and the servovalve's time constant as a spool lag.
"""

from __future__ import annotations

import dataclasses
from functools import cache

from vtable.controllers import kinds
from vtable.errors import VtableError
from vtable.params.table import ServoConstants
from vtable.params.virtual import VirtualTable
from vtable.runs.table import table_from_dict
from vtable.tables.eerc import virtual_table
from vtable.tables.lab import actuator_servo, described_table


def lab_table(desc=None) -> VirtualTable:
    """The table of a run's [table] description (None: the EERC table), as every model
    reads it."""
    if desc is None or (desc.preset == "eerc" and _only_preset(desc)):
        return _eerc_default()
    return _described(desc, _eerc_default() if desc.preset == "eerc" else None)


@cache
def _eerc_default() -> VirtualTable:
    return virtual_table()


def _only_preset(desc) -> bool:
    return all(getattr(desc, f.name) is None for f in dataclasses.fields(desc)
               if f.name not in ("preset", "notes", "dofs", "mass", "pitch_inertia",
                                 "horizontal", "controller", "limits")) and \
        _same_as_preset(desc)


def _same_as_preset(desc) -> bool:
    return desc == table_from_dict({"preset": desc.preset}, "preset")


def _check_modelled(desc, base: VirtualTable | None, n: int, where: str) -> None:
    """vtable models the EERC table (its five DOFs, its three horizontal actuators) and
    uniaxial platens: a description asking for another table is refused, not half-read."""
    dofs = desc.dofs or (base.dofs if base else ("x",))
    if tuple(dofs) == ("x",):
        return
    if base is None or set(dofs) != set(base.dofs):
        eerc = ", ".join(_eerc_default().dofs)
        raise VtableError(f"{where}.dofs: vtable models the EERC table (DOFs {eerc}) or a "
                          f"uniaxial platen (dofs = [\"x\"]), not DOFs {', '.join(dofs)}")
    if n != base.n_actuators:
        raise VtableError(f"{where}.horizontal.count: the EERC table has {base.n_actuators} "
                          f"horizontal actuators (Table 2.1), not {n}; a table of another "
                          "count is described without the preset")


def _described(desc, base: VirtualTable | None) -> VirtualTable:
    """A table from its description (over `base`, the preset's own model, when given)."""
    where = f"[table]{' preset ' + repr(desc.preset) if desc.preset else ''}"
    h = desc.horizontal
    c = desc.controller
    mass = desc.mass or (base.platen_mass if base else None)
    if mass is None:
        raise VtableError(f"{where}: the platen mass is not given (platen_mass_kg)")
    n = (h.count if h and h.count else None) or (base.n_actuators if base else 1)
    _check_modelled(desc, base, n, where)
    s0 = actuator_servo(base) if base else None

    def pick(attr, fallback):
        v = getattr(h, attr) if h is not None else None
        if v is not None:
            return v
        if fallback is None:
            raise VtableError(f"{where}.horizontal: {attr} is not given")
        return fallback

    area = pick("piston_area", s0.area if s0 else None)
    volume = pick("oil_volume", s0.volume if s0 else None)
    beta = pick("bulk_modulus", s0.beta if s0 else None)
    leak = pick("leakage", s0.k_ct if s0 else 0.0)
    damping = (h.damping if h is not None and h.damping is not None else
               (s0.damping or 0.0) * n if s0 else 0.0)
    tau = h.valve_time_constant if h is not None and h.valve_time_constant is not None else \
        (base.valve_lag if base else 0.0)
    kind = (c.kind if c is not None and c.kind else None) or (base.controller if base
                                                              else "pid")
    kind_of = kinds.get(kind)
    control = None
    if c is not None:
        try:
            control = kind_of.stage_use(c)
        except VtableError as e:
            raise VtableError(f"{where}.controller: {e}") from None
    if kind != "three_variable":
        flow_gain = pick("valve_flow_gain", None)
        dgain = c.displacement_gain if c is not None else None
        if not dgain:
            raise VtableError(f"{where}.controller: a {kind} controller needs "
                              "displacement_gain_v_per_m (the transducer's volts per metre)")
        P = c.p if c.p is not None else 1.0
        if not P > 0:
            raise VtableError(f"{where}.controller.p: vtable's models need p > 0 (the loop's "
                              "gain is read per unit of k_d p)")
        # u = P K_d (x_c - x) - K_pg P_L - K_vg ẋ volts, q = K_q u: the report's law
        # q = k_t [(x_c - x) - k_p P_L - k_v ẋ] with k_t = K_q K_d P
        k_t = flow_gain * dgain * P
        k_p = (c.pressure_gain or 0.0) / (dgain * P)
        k_v = (c.velocity_gain or 0.0) / (dgain * P)
        servo = ServoConstants(k_p=k_p, k_t=k_t, k_ct=leak,
                               rc=0.01, mass=mass / n, beta=beta, area=area, volume=volume,
                               k_v=k_v, damping=damping / n,
                               source=f"{where}: k_t = valve flow gain x displacement gain x P")
    else:
        if s0 is None:
            raise VtableError(f"{where}.controller: the three_variable controller's constants "
                              "come from the EERC preset (Table B.5); describe a pid instead")
        servo = dataclasses.replace(s0, area=area, volume=volume, beta=beta, k_ct=leak,
                                    mass=mass / n, damping=damping / n or None)
    lim = desc.limits

    def limit(key: str):  # the declaration's, else the preset's, else absent
        v = getattr(lim, key) if lim else None
        return v if v else getattr(base, key) if base else None

    return described_table(
        name=desc.preset or "described", dofs=desc.dofs or (base.dofs if base else ("x",)),
        platen_mass=mass, pitch_inertia=desc.pitch_inertia or (base.pitch_inertia if base
                                                                 else None),
        com_height=desc.com_height if desc.com_height is not None else
        (base.com_height if base else None),
        n_actuators=n, servo=servo, valve_lag=tau, controller=kind, control=control,
        limits={k: limit(k) for k in ("stroke", "velocity", "acceleration", "payload", "band")},
        force_measured=(h.force_measured if h is not None and h.force_measured else
                        base.force_measured if base else "load_cell"))


def run_table(run) -> VirtualTable:
    """The table a run was made on (its [table]; the EERC table when it has none)."""
    return lab_table(run.table())
