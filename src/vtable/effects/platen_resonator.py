"""platen_resonator: a mass–spring–damper on the platen that the run does not declare (an
undocumented specimen, a reaction-mass or table bending mode).

A mass m_r on a spring k_r = m_r ω_r² and dashpot c_r = 2 ξ_r m_r ω_r to the platen adds
the impedance m_r (c_r s + k_r)/(m_r s² + c_r s + k_r) to the platen's mass in the oil
column's load (the table carrying an SDOF structure of report ch. 7, eq 7.7, with an SDOF
that nobody declared): x_t/x_c dips near f_r, where the resonator holds the platen, and
peaks just above, where it swings with it. Its mass is a fraction of the run's table's platen mass
(`m.table.platen_mass`), so one set of bounds fits any table.
"""

from __future__ import annotations

import math
import statistics

from vtable.effects.base import Effect, Param
from vtable.ident.undeclared import undeclared_resonance


class PlatenResonator(Effect):
    name = "platen_resonator"
    physics = ("an undeclared mass m_r on a spring and dashpot (f_r, ξ_r) to the platen: an "
               "undocumented specimen, a reaction-mass or table bending mode")
    section = "ch. 7 (a table carrying an SDOF, eq 7.7), undeclared"
    signature = ("a notch in x_t/x_c at f_r and a peak just above it (the report's "
                 "interaction signature) that no declared specimen mode explains")
    params = (Param("m_r", "%", 10.0, 1.0, 300.0, log=True, source="assumed",
                    doc="the resonator's mass, % of the platen mass"),
              Param("f_r", "Hz", 10.0, 1.0, 60.0, log=True, source="assumed",
                    doc="its natural frequency on a fixed platen"),
              Param("xi_r", "1", 0.05, 0.005, 0.3, log=True, source="assumed",
                    doc="its damping ratio"))

    def evidence(self, campaign):
        """The resonance identify's structure check finds on the runs that declare no
        specimen with a mode (`vtable.ident.undeclared`): the median over those runs of
        its frequency, and of its damping and mass ratio (eq 7.9's u, the platen's mass
        fraction) over the runs that resolve them (a short record may resolve the
        frequency alone: the others then start at their defaults)."""
        found = [r for r in map(undeclared_resonance, campaign.runs) if r is not None]
        if not found:
            return None
        med = statistics.median
        values = {"f_r": med(r.f_s for r in found)}
        if us := [r.u for r in found if r.u is not None]:
            values["m_r"] = 100.0 * med(us)
        if xis := [r.xi_s for r in found if r.xi_s is not None]:
            values["xi_r"] = med(xis)
        runs = ", ".join(r.run for r in found)
        alone = "" if len(values) == 3 else (
            "; the records resolve " + ("its frequency alone" if len(values) == 1 else
                                        "not all of it"))
        return values, f"identified on {runs}'s x_t/x_c (eq 7.9 with the valve lag){alone}"

    def apply(self, m, p):
        mass = p["m_r"] * m.table.platen_mass  # p["m_r"] is in SI: a fraction
        w = 2 * math.pi * p["f_r"]
        m.add_structure("resonator", mass, mass * w * w, 2 * p["xi_r"] * w * mass)


EFFECT = PlatenResonator()
