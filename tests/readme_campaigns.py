"""Issue 18's README campaigns: made with `vtable simulate` as the README shows (the SDOF
frame on Berkeley's table; random 0-25 Hz at 0.1 and 0.25 in, 11 s, and El Centro at 4 in),
one catalog effect hidden with `--effect`, noise-free or with `--noise`. The virtual table
always has its own pitch system and Table B.5's RC filter on ΔP, which the bare reduced
model lacks, so the exact set a diagnosis must end with is {pitch_flexibility,
force_feedback_filter} plus the hidden effect (`expected`). Used by
tests/acceptance/test_readme_campaigns.py and benchmarks/bench_readme_campaigns.py."""

from __future__ import annotations

from pathlib import Path

from vtable import verbs
from vtable.effects.registry import BUILT_IN

#: what the virtual table itself has and the bare reduced model lacks
OWN = ("force_feedback_filter", "pitch_flexibility")
#: the hidden doses (in the effect's units); the others at their defaults. flow_saturation's
#: default rated flow (25 in/s) is above the campaign's peak table velocity (14.6 in/s, El
#: Centro at 4 in): at its default it never acts, so it is hidden at 10 in/s.
#: oil_column_air at its default 1 % lowers the oil column's frequency (f_o 14.97 -> 13.8 Hz),
#: which the free servo loop absorbs; what is left, its pressure dependence, changes the
#: held-out error by 0.2 % (0.54 % -> 0.33 %), below the reduced model's resolution: at 1 %
#: it is a loop to calibrate, not an effect to add, so it is hidden at 4 %
DOSE = {"actuator_friction": "friction=3", "flow_saturation": "v_max=10",
        "oil_column_air": "air_ratio=0.04"}
#: the README's three commands: `vtable simulate` arguments
COMMANDS = (("random_0.1", dict(kind="random", band=(0.0, 25.0), peak=0.1, duration=11.0,
                                seed=1)),
            ("random_0.25", dict(kind="random", band=(0.0, 25.0), peak=0.25, duration=11.0,
                                 seed=2)),
            ("elcentro", dict(kind="earthquake", record="elcentro", peak=4.0, seed=3)))


#: the catalog's effects of the specimen rather than the table: a yielding storey is hidden
#: in the scorecard's yielding campaigns (tests/scorecard.py, CASES_21), not on the frame
SPECIMEN_EFFECTS = ("storey_yield",)


def hidden_cases() -> list[str | None]:
    """None (nothing hidden), then every catalog effect the standard table lacks."""
    return [None] + [e for e in BUILT_IN if e not in OWN and e not in SPECIMEN_EFFECTS]


def campaign(hidden: str | None, noise: float, root: Path) -> list[str]:
    """The campaign's run files (made once, cached)."""
    folder = root / f"{hidden or 'none'}-noise{noise:g}"
    paths = [folder / f"{name}.toml" for name, _ in COMMANDS]
    if all(p.exists() for p in paths):
        return [str(p) for p in paths]
    folder.mkdir(parents=True, exist_ok=True)
    spec = [] if hidden is None else [f"{hidden}:{DOSE[hidden]}" if hidden in DOSE
                                      else hidden]
    for (_, kw), p in zip(COMMANDS, paths, strict=True):
        verbs.simulate("sdof_frame", effects=spec, out=str(p.with_suffix("")), noise=noise,
                       **kw)
    return [str(p) for p in paths]


def expected(hidden: str | None) -> list[str]:
    """The exact set a diagnosis of the campaign must end with."""
    return sorted({*OWN, *([hidden] if hidden else [])})
