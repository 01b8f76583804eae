"""What the actuator force channels measure, where the runs do not say.

A run's ``[table.horizontal] force_measured`` declares what its force channels read: the
force the rod transmits to the platen ("load_cell") or A·ΔP, the pressure force of eq 6.3
("delta_p"). The two differ by the force stages between them — friction, F_r sign(ẋ)
(eq C.12) — and are the same without one. A campaign whose runs hold force channels and
declare neither is read as the table's preset reads them (`VirtualTable.force_measured`),
and a diagnosis whose model holds a force stage then fits the other reading once
(`force_reading`). It is kept when its held-out gain passes the statistical criteria of
`SELECTION` as an effect's must (`selection.failing`: a reading has no parameter, so no
prior): the runs then measured A·ΔP where a load cell was assumed, or the reverse, and a
friction fitted to the wrong reading leaves the force residual of a missing effect (or is
misfitted). Either way the diagnosis says what it tried (`Diagnosis.force_reading`).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from vtable.diagnose.compare import compare
from vtable.diagnose.groups import GROUPS
from vtable.diagnose.selection import failing
from vtable.diagnose.statistics import held_out_gain
from vtable.errors import VtableError
from vtable.models.reduced import ReducedModel

#: each reading and the other one
OTHER = {"load_cell": "delta_p", "delta_p": "load_cell"}
#: how the findings name a reading
SAID = {"load_cell": "the force the rod transmits (a load cell)",
        "delta_p": "A·ΔP (the pressure force)"}


def undeclared(runs) -> bool:
    """Whether `runs` hold actuator force channels and none declares what they measure."""
    forces = set(GROUPS["actuator force"])
    if not any(forces & set(r.channels) for r in runs):
        return False
    for r in runs:
        desc = r.table()
        if desc is not None and desc.horizontal is not None \
                and desc.horizontal.force_measured is not None:
            return False
    return True


def force_stage(ph, vt) -> bool:
    """Whether model `ph` on table `vt` holds a force stage (the two readings differ)."""
    try:
        stages = ReducedModel(ph, vt, kernels=False).assembly.stages
    except VtableError:
        return False
    return any(s.kind == "force" for s, _ in stages)


def force_reading(dg, st) -> tuple[Any, float, float] | None:
    """Diagnoser `dg`'s current model (loop state `st`) refitted with the other reading of
    the force channels, once, where the runs do not declare it and the model holds a force
    stage; the refit becomes the current model and the last stage when its held-out gain
    passes (`SELECTION`'s criteria). Returns (physics, held-out error, training cost) of the
    refit kept, else None. `st.reading` records the test (`Diagnosis.force_reading`)."""
    if st.reading is not None or st.current is None or not st.stages \
            or not undeclared(dg.runs) or not force_stage(st.current, dg.vt):
        return None
    assumed = st.current.force_measured or dg.vt.force_measured
    other = OTHER[assumed]
    m = dg.model(dataclasses.replace(st.current, force_measured=other),
                 choose=False).fit(dg.campaign)
    pred = m.predictions(dg.campaign)
    err = compare(pred, dg.runs, scored="held", floor=dg.floor).error
    g = held_out_gain(st.stages[-1].predictions, pred, dg.runs, dg.campaign.noise)
    why = failing(g, m.physics_)  # the resolution of the model with the reading (no prior)
    st.reading = {"declared": None, "assumed": assumed, "tried": other,
                  "found": assumed if why else other, "error_before": st.err,
                  "error_after": err, "z": g.z if g is not None else None,
                  "why_not": "; ".join(why), "after_round": len(st.rounds)}
    if why:
        dg.notes.append(f"the runs do not declare what their force channels measure: read as "
                        f"{SAID[assumed]}; {SAID[other]} would change the held-out error "
                        f"{st.err:.2%} -> {err:.2%}, not kept: {'; '.join(why)}")
        return None
    st.adopt(f"force_{other}", m.physics_, err, pred)
    return m.physics_, err, m.cost_

