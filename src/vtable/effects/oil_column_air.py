"""oil_column_air: entrained air lowers the oil's effective bulk modulus and makes it
pressure dependent, 1/β_e = 1/β + r/(1.4 P) per chamber (eqs 8.5, C.10), the chambers at
P_s/2 ± P_L/2: a softer oil column, a lower open-loop frequency f_o."""

from __future__ import annotations

from vtable.effects.base import Effect, Param


class OilColumnAir(Effect):
    name = "oil_column_air"
    physics = ("entrained air lowers the effective bulk modulus and makes it pressure "
               "dependent, 1/β_e = 1/β + r/(1.4 P)")
    section = "eq 8.5, C.10"
    signature = "lower open-loop frequency f_o; a softer oil column"
    params = (Param("air_ratio", "1", 0.01, 1e-4, 0.2, log=True, source="eq C.10's r, assumed"),)

    def apply(self, m, p):
        m.set_servo(air_ratio=p["air_ratio"])


EFFECT = OilColumnAir()
