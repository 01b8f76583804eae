"""Campaigns of several specimen states (issue 32, deliverable 3).

Runs that declare `[specimen] state` are fitted with the specimen's parameters per state
from the start (`Campaign.states`, `layout.state_params`): the table, the servo loop and
every effect are shared. A campaign that declares none, whose runs do not hold one plant the
final model describes (`plants.plant_differences`: x_t/x_c differ beyond their confidence
and beyond the model's own difference), is refitted with a state per run (`split`), kept
when its held-out gain passes the selection's statistical criteria as an effect's must
(`selection.failing`; no prior: each state's specimen keeps its declaration's bounds and
priors) and removes `STATES_SHARE` of the systematic residual. Either way the states'
fitted specimens are reported (`state_rows`).
"""

from __future__ import annotations

from typing import Any

from vtable.diagnose.compare import compare
from vtable.diagnose.noise import within_noise
from vtable.diagnose.plants import PlantDifference, plant_differences
from vtable.diagnose.screen import ChangeEvidence, residual_change
from vtable.diagnose.selection import failing
from vtable.diagnose.statistics import held_out_gain

#: the share of the systematic residual a state per run must remove (an effect needs
#: `selection.MIN_SHARE`; the states bring a specimen's parameters per run, and a model-form
#: difference between runs of one specimen, a law not quite the truth's, is not a state)
STATES_SHARE = 0.5


def differences(dg, st) -> list[PlantDifference] | None:
    """The pairs of diagnoser `dg`'s runs that do not hold one plant the current model
    describes (`plant_differences` of its stage's predictions, worked out once for them),
    or None where not asked: the campaign declares its states, has one run, or no model
    is fitted yet."""
    if dg.campaign.states or len(dg.runs) < 2 or st.current is None:
        return None
    pred = st.stages[-1].predictions
    if st.plant_pairs is None or st.plant_pairs[0] is not pred:
        st.plant_pairs = (pred, plant_differences(dg.runs, pred))
    return st.plant_pairs[1]


def unexplained(dg, st) -> ChangeEvidence | None:
    """What the current (time-invariant) model's residual says of a change within the runs
    (`screen.residual_change`), where its held-out error is above `NOISE_FACTOR` x the noise
    floor and the runs hold one plant; None otherwise. Runs that differ as plants
    are the states' to explain (`split`, after the rounds), not a change within a run: a
    campaign whose specimen changes from run to run is read so, not as degrading."""
    if within_noise(st.err, dg.floor) or differences(dg, st):
        return None
    return residual_change(dg.campaign, st.stages[-1].predictions)


def split(dg, st) -> list[PlantDifference] | None:
    """Diagnoser `dg`'s final model refitted with a specimen state per run, where its
    campaign declares no states and its runs do not hold one plant; the refit becomes the
    last stage (and `dg.campaign` the split campaign) when it passes. Returns the pairs of
    runs that differed before it (empty: none), None when not looked for (the campaign
    declares its states, has one run, or the model is not calibrated)."""
    camp = dg.campaign
    pairs = differences(dg, st) if dg.calibration.enabled else None
    if not pairs:
        return pairs
    per_run = camp.with_states({r.name: r.name for r in dg.runs})
    m = dg.model(st.current, choose=False).fit(per_run)
    pred = m.predictions(per_run)
    err = compare(pred, dg.runs, scored="held", floor=dg.floor).error
    g = held_out_gain(st.stages[-1].predictions, pred, dg.runs, camp.noise)
    why = failing(g)
    if g.share < STATES_SHARE:
        why.append(f"it removes {max(g.share, 0):.0%} of the systematic residual (a state "
                   f"per run needs {STATES_SHARE:.0%}: it has a specimen's parameters per run)")
    if why:
        dg.notes.append(f"a specimen state per run would change the held-out error "
                        f"{st.err:.2%} -> {err:.2%}, not kept: {'; '.join(why)}")
        return pairs
    dg.campaign = per_run
    st.adopt("states", m.physics_, err, pred)
    st.split = True
    return pairs


def state_rows(base: dict[str, dict[str, Any]], states: dict[str, list[str]]
               ) -> dict[str, dict[str, Any]]:
    """Each state -> its runs and its specimen's fitted parameters (the `base` table's
    "specimen.*" rows for the first state, "specimen[STATE].*" for the others)."""
    out = {}
    for i, (s, runs) in enumerate(states.items()):
        prefix = "specimen." if i == 0 else f"specimen[{s}]."
        out[s] = {"runs": list(runs),
                  "specimen": {k.removeprefix(prefix): v["fitted"] for k, v in base.items()
                               if k.startswith(prefix)}}
    return out
