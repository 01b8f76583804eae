"""Spool overlap in the horizontal servovalves: no flow while the spool is within
±overlap of null — a dead band on the valve's flow stage."""

from vtable.effects import Effect, Param, register
from vtable.hydraulics import Stage


def overlapped(q, P, p):
    """The valve flow q of a spool overlapped by p.q_o (as flow): none within ±q_o of
    null, beyond it the flow of the travel past the lands."""
    if q > p.q_o:
        return q - p.q_o
    if q < -p.q_o:
        return q + p.q_o
    return 0.0


OVERLAP = Stage("spool_overlap", "flow", overlapped, ("q_o",), order=-1,
                extensive=("q_o",))


class ValveOverlap(Effect):
    name = "valve_overlap"
    physics = "the servovalve's spool overlaps its ports: no flow within ±overlap of null"
    section = "not in the report (a lab's suspicion)"
    signature = "small spans lose more than large ones; a flat spot at motion reversals"
    params = (Param("overlap", "%", 1.0, 0.01, 20.0, log=True,
                    source="assumed; of the spool's stroke, as the rated flow"),)

    def apply(self, m, p):
        m.add_stage(OVERLAP, q_o=p["overlap"] * m.table.rated_flow)


register(ValveOverlap())
