"""Appendix C's valve on the horizontal actuators, as one set of `HydraulicParams`
options: turbulent orifice flow from the supply pressure (eq C.14), the spool stroke
limit as a rated-flow cap, and optionally entrained air (eq C.10) and Coulomb friction
(eq C.12). The defaults rate the full spool at the supply pressure, so the unloaded
actuator's top speed is the rated flow over the piston area — the table's 25 in/s (§2.2,
Table 2.2)."""

from __future__ import annotations

from vtable.hydraulics.element import HydraulicParams


def appendix_c(base: HydraulicParams, supply_pressure: float, rated_flow: float,
               rc: float | None = None, air_ratio: float = 0.0,
               friction: float = 0.0) -> HydraulicParams:
    """`base` (one actuator, SI) with the appendix C valve: supply pressure (Pa), rated
    flow at full spool (m³/s), the RC filter kept unless `rc` says otherwise."""
    return base.replace(supply_pressure=supply_pressure, max_flow=rated_flow,
                        air_ratio=air_ratio, friction=friction,
                        rc=base.rc if rc is None else rc)
