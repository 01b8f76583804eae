"""Backlash in the horizontal actuators' swivels: a dead band between piston and platen."""

import math

from vtable.effects import Effect, Param, register

PISTONS = 680.0  # kg: pistons, rods and swivels of H1-H3 together (assumed)
CONTACT_HZ = 50.0  # Hz: the platen on the closed swivels (assumed)


def dead_band(d, v, z, p, dz):
    """Force on the pistons from the platen (d, v: travel relative to it): a spring taking
    up beyond the free play ±gap/2 (smoothly, as contact surfaces do), and contact damping."""
    half, k, c = 0.5 * p.gap, p.k, p.c
    engaged = math.tanh(d / half) ** 2
    return -k * (d - half * math.tanh(d / half)) - c * engaged * v


class SwivelBacklash(Effect):
    name = "swivel_backlash"
    physics = "free play in the horizontal actuators' swivels: a dead band piston-platen"
    section = "not in the report (a lab's suspicion)"
    signature = "jerks in the table acceleration at motion reversals; the platen lags"
    params = (Param("gap", "in", 0.01, 0.001, 0.2, log=True, source="assumed"),)

    def apply(self, m, p):
        k = m.table.platen_mass * (2 * math.pi * CONTACT_HZ) ** 2  # the run's platen
        c = 0.4 * math.sqrt(k * PISTONS)  # contact damping, 20 % of the pistons' mode
        m.insert_at_actuators("piston", PISTONS, dead_band, {"gap": p["gap"], "k": k, "c": c},
                              stiffness=k)


register(SwivelBacklash())
