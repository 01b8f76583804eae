"""oil_column_air: entrained air lowers the oil's effective bulk modulus and makes it
pressure dependent, 1/β_e = 1/β + r/(1.4 P) per chamber (eqs 8.5, C.10), the chambers at
P_s/2 ± P_L/2: a softer oil column, a lower open-loop frequency f_o — a pressure stage of
the hydraulic element. `chamber_modulus` is the single-chamber law (eq 8.5) every model
calls."""

from __future__ import annotations

from vtable._numba import njit
from vtable.effects.base import Effect, Param
from vtable.hydraulics.stage import Stage

ATM = 101325.0  # Pa: the chamber pressure floor of the air law


@njit(cache=True)
def chamber_modulus(beta, air_ratio, pressure):
    """One chamber's effective bulk modulus at absolute pressure P (eq C.10):
    1/β_e = 1/β + r/(1.4 P)."""
    return 1.0 / (1.0 / beta + air_ratio / (1.4 * pressure))


def air(beta, P, p):
    """The oil column's modulus at load pressure P (eqs C.6-C.11): each chamber (V/2) at
    P_s/2 ± P/2 (floored at 0 gauge) has its own modulus, Ṗ_L = (2/V)(β₁ + β₂)·flow."""
    p1 = max(0.5 * p.mean_pressure + 0.5 * P, 0.0) + ATM
    p2 = max(0.5 * p.mean_pressure - 0.5 * P, 0.0) + ATM
    return 0.5 * chamber_modulus(beta, p.air_ratio, p1) + \
        0.5 * chamber_modulus(beta, p.air_ratio, p2)


AIR = Stage("entrained_air", "pressure", air, ("air_ratio", "mean_pressure"))


class OilColumnAir(Effect):
    name = "oil_column_air"
    physics = ("entrained air lowers the effective bulk modulus and makes it pressure "
               "dependent, 1/β_e = 1/β + r/(1.4 P)")
    section = "eq 8.5, C.10"
    signature = "lower open-loop frequency f_o; a softer oil column"
    params = (Param("air_ratio", "1", 0.01, 1e-4, 0.2, log=True, source="eq C.10's r, assumed"),)
    stages = (AIR,)

    def apply(self, m, p):
        m.add_stage(AIR, air_ratio=p["air_ratio"], mean_pressure=m.table.supply_pressure)


EFFECT = OilColumnAir()
