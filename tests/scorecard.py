"""The diagnosis scorecard (issue 12): generated cases with a hidden truth, their campaigns
made by the independent truth simulator (tests/truth, not vtable's own simulator), the
diagnosis of each, and the acceptance rules. Shared by benchmarks/bench_diagnosis_scorecard.py
and tests/test_scorecard.py.

Every case is three runs of one configuration: band-limited random 0-25 Hz at two spans
(`RANDOM_S` s each) and an earthquake (El Centro 1940 NS or a synthetic Kanai-Tajimi record,
time-compressed by 1.811 as in §9.2, ~26 s and ~18 s). The specimen is the §2.4 SDOF frame
(68 kip at 219 in, 2.87 Hz) or a 3-storey shear building (floor1_acc..floor3_acc written);
the DECLARED specimen differs from the truth within the calibration bounds (frequency 2-4 %,
damping x/÷ 1.2-2, weights 2-8 %) except in the exact-null cases. The table is the EERC
table with its Table B.5 constants; when pitch_flexibility is hidden, the truth's pitch
family is `hybrid` (eq 8.37) or `two_directional` (eq 8.16), with the platen's c.o.m. on
the actuator line (0) or as vtable's EERC preset declares it (`DECLARED_COM_IN`).

Acceptance (issue 12): the final effect set is exactly the hidden set in >= 90 % of the
in-catalog cases; nothing is added in a null or mis-declared-null case; in every
outside-catalog case `unexplained` is not null (no built-in effect is claimed to close the
gap); on the null cases the calibrated base ends within 0.5 % of the truth's every mode
frequency and within 20 % of its damping (`calibration_errors`).

Caches (not in the repository): `cache_root()` = $VTABLE_SCORECARD_CACHE or
~/.cache/vtable-scorecard. Campaigns live under campaigns/NAME-KEY (KEY hashes the case
definition and the generator's version), diagnosis results under results/NAME-KEY.json
(KEY hashes the case definition and every source file of the vtable package, so a changed
engine is diagnosed again).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # the benchmark imports this file from outside pytest
    sys.path.insert(0, str(HERE))

import truth  # noqa: E402

GENERATOR_VERSION = 2  # bump when the campaign a case definition makes changes
RANDOM_S = 12.0  # s, each random run
SPANS_IN = (0.1, 0.5)  # peak command of the two random runs
QUAKE_PEAK_IN = 3.0  # peak command of the earthquake run (El Centro reaches ~17 in/s)
#: vtable's EERC preset: slab + ribs c.o.m. above the horizontal actuator line (in), the
#: value the run's [table] preset = "eerc" declares (tests/test_truth.py uses the same)
DECLARED_COM_IN = 20.2

KINDS = ("in_catalog", "null", "misdeclared_null", "outside")


@dataclass(frozen=True)
class Case:
    """One scorecard case. `effects` are the truth's (tests/truth/tables.py names and
    units); `hidden` is what a perfect diagnosis finds (the in-catalog part)."""

    name: str
    kind: str  # one of KINDS
    effects: dict[str, dict[str, float]] = field(default_factory=dict)
    specimen: str = "sdof"  # "sdof" | "3storey"
    pitch: str = "none"  # truth table family: "none" | "hybrid" | "two_directional"
    com_height_in: float = 0.0
    fs: float = 200.0
    noise: float = 0.02
    record: str = "elcentro"  # "elcentro" | "synthetic"
    seed: int = 1
    perturb: tuple[float, float, float] | None = (0.03, 1.5, 0.05)  # frequency, damping, weight

    def definition(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["perturb"] = list(self.perturb) if self.perturb else None
        d.update(random_s=RANDOM_S, spans_in=list(SPANS_IN), quake_peak_in=QUAKE_PEAK_IN)
        return d

    @property
    def hidden(self) -> list[str]:
        return sorted(e for e in self.effects if e not in truth.OUTSIDE_CATALOG)

    @property
    def outside(self) -> list[str]:
        return sorted(e for e in self.effects if e in truth.OUTSIDE_CATALOG)

    def key(self, extra: str = "") -> str:
        text = json.dumps(self.definition(), sort_keys=True) + f"|gen{GENERATOR_VERSION}|{extra}"
        return hashlib.sha256(text.encode()).hexdigest()[:12]

    # -- the truth ------------------------------------------------------------------------
    def true_specimen(self) -> truth.Specimen:
        if self.specimen == "sdof":
            return truth.sdof(68.0, 219.0, 2.87, 0.02)  # §2.4 frame, 2 % damping
        if self.specimen == "3storey":
            # 3 x 25 kip at 110/160/210 in, storeys 120/100/80 kip/in: 2.9, 7.5, 11.1 Hz
            return truth.building([25.0, 25.0, 25.0], [110.0, 160.0, 210.0],
                                  storey_k_kip_in=[120.0, 100.0, 80.0], xi=0.02)
        raise ValueError(f"case {self.name}: unknown specimen {self.specimen!r}")

    def declared_specimen(self) -> truth.Specimen:
        spec = self.true_specimen()
        if self.perturb is None:
            return spec
        f, d, w = self.perturb
        if self.specimen == "3storey":
            # truth.perturb also changes the mode shape (storeys independently) and the
            # floor weights one by one: 3/4 of the bounds keep every mode within ±5 %
            f, w = 0.75 * f, min(w, 0.05)
        return truth.perturb(spec, seed=self.seed + 1000, frequency=f, damping=d, weight=w)

    def table(self) -> truth.Table:
        return truth.eerc_table(pitch=self.pitch, com_height_in=self.com_height_in,
                                effects=self.effects)


# ---------------------------------------------------------------------------------------------
# the cases


def _cases() -> list[Case]:
    C = Case
    doses = [  # (effect, dose 1, dose 2): what a lab would see and these runs can reveal
        ("force_feedback_filter", {"rc": 0.005}, {"rc": 0.01}),
        ("valve_flow_nonlinearity", {"supply_pressure": 3000.0}, {"supply_pressure": 2000.0}),
        ("actuator_friction", {"friction": 1.5}, {"friction": 3.0}),
        ("flow_saturation", {"v_max": 15.0}, {"v_max": 10.0}),
        ("valve_dynamics", {"tau": 0.003}, {"tau": 0.006}),
        ("oil_column_air", {"air_ratio": 0.02}, {"air_ratio": 0.04}),
        ("amplitude_dependent_damping", {"gamma": 0.03}, {"gamma": 0.1}),
        ("foundation_compliance", {"f_f": 15.0, "xi_f": 0.1}, {"f_f": 8.0, "xi_f": 0.1}),
        ("sensor_filter", {"cutoff_hz": 100.0}, {"cutoff_hz": 60.0}),
    ]
    rates = (200.0, 256.0, 500.0)
    noises = (0.01, 0.02, 0.03)
    perturbs = ((0.02, 1.44, 0.04), (0.03, 1.5, 0.05), (0.04, 2.0, 0.08))
    out: list[Case] = []
    i = 0

    def vary(**kw) -> dict:
        nonlocal i
        d = dict(fs=rates[i % 3], noise=noises[(i // 3) % 3], perturb=perturbs[(i + 1) % 3],
                 seed=10 + i)
        i += 1
        d.update(kw)
        return d

    # every catalog effect at two doses (flow saturation needs El Centro: it reaches 17 in/s)
    out.append(C("pitch_t81_hybrid", "in_catalog", {"pitch_flexibility": {}}, pitch="hybrid",
                 **vary(com_height_in=DECLARED_COM_IN)))
    out.append(C("pitch_soft_2dir", "in_catalog",
                 {"pitch_flexibility": {"k_theta": 1.1e10, "c_theta": 2.6e8}},
                 pitch="two_directional", **vary(com_height_in=0.0, record="synthetic")))
    for name, d1, d2 in doses:
        for j, dose in enumerate((d1, d2)):
            rec = "elcentro" if name == "flow_saturation" or j == 0 else "synthetic"
            out.append(C(f"{name}_{j + 1}", "in_catalog", {name: dose},
                         **vary(record=rec, specimen="3storey" if (i % 4 == 3) else "sdof")))
    # pairs and a triple
    out.append(C("friction+valve_lag", "in_catalog",
                 {"actuator_friction": {"friction": 3.0}, "valve_dynamics": {"tau": 0.006}},
                 **vary()))
    out.append(C("pitch+rc_filter", "in_catalog",
                 {"pitch_flexibility": {}, "force_feedback_filter": {"rc": 0.01}},
                 pitch="hybrid", **vary(com_height_in=DECLARED_COM_IN, record="synthetic")))
    out.append(C("flowcap+air", "in_catalog",
                 {"flow_saturation": {"v_max": 12.0}, "oil_column_air": {"air_ratio": 0.04}},
                 **vary(specimen="3storey")))
    out.append(C("foundation+sensor", "in_catalog",
                 {"foundation_compliance": {"f_f": 8.0, "xi_f": 0.1},
                  "sensor_filter": {"cutoff_hz": 60.0}}, **vary(record="synthetic")))
    out.append(C("pitch+friction+valve_lag", "in_catalog",
                 {"pitch_flexibility": {}, "actuator_friction": {"friction": 1.5},
                  "valve_dynamics": {"tau": 0.003}}, pitch="two_directional",
                 **vary(com_height_in=DECLARED_COM_IN)))
    # 3-storey in-catalog cases
    out.append(C("3storey_friction", "in_catalog", {"actuator_friction": {"friction": 3.0}},
                 **vary(specimen="3storey")))
    out.append(C("3storey_pitch", "in_catalog", {"pitch_flexibility": {}}, pitch="hybrid",
                 **vary(specimen="3storey", com_height_in=0.0, record="synthetic")))
    # null: declared exactly; mis-declared null: declared within the calibration bounds
    for spec, rec in (("sdof", "elcentro"), ("3storey", "synthetic"), ("sdof", "synthetic")):
        out.append(C(f"null_{spec}_{rec}", "null", {}, **vary(specimen=spec, record=rec,
                                                              perturb=None)))
    for spec, rec, p in (("sdof", "elcentro", (0.04, 2.0, 0.08)),
                         ("sdof", "synthetic", (0.02, 1.5, 0.05)),
                         ("3storey", "elcentro", (0.03, 1.5, 0.05)),
                         ("3storey", "synthetic", (0.04, 2.0, 0.08))):
        out.append(C(f"misdeclared_{spec}_{rec}", "misdeclared_null", {},
                     **vary(specimen=spec, record=rec, perturb=p)))
    # outside the catalog
    out.append(C("backlash_1", "outside", {"backlash": {"gap_in": 0.005}}, **vary()))
    out.append(C("backlash_2", "outside", {"backlash": {"gap_in": 0.02}},
                 **vary(record="synthetic")))
    out.append(C("backlash_3storey", "outside", {"backlash": {"gap_in": 0.01}},
                 **vary(specimen="3storey")))
    out.append(C("yielding_1", "outside",
                 {"yielding_storey": {"yield_fraction": 1.0, "post_yield_ratio": 0.05}}, **vary()))
    out.append(C("yielding_2", "outside",
                 {"yielding_storey": {"yield_fraction": 0.5, "post_yield_ratio": 0.02}},
                 **vary(specimen="3storey")))
    out.append(C("pump_drop", "outside",
                 {"valve_flow_nonlinearity": {"supply_pressure": 3000.0},
                  "pump_pressure_drop": {"drop_psi_per_gpm": 5.0}}, **vary()))
    return out


CASES: list[Case] = _cases()
BY_NAME: dict[str, Case] = {c.name: c for c in CASES}
#: a small subset, each a different kind (the test's and `--quick`'s): a mis-declared null,
#: one in-catalog effect, one outside the catalog; synthetic records (short runs)
QUICK = ("misdeclared_sdof_synthetic", "actuator_friction_2", "backlash_2")


# ---------------------------------------------------------------------------------------------
# caches


def cache_root() -> Path:
    env = os.environ.get("VTABLE_SCORECARD_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "vtable-scorecard"


def campaign(case: Case, root: Path | None = None) -> list[Path]:
    """The case's three run files (RUN.toml paths), generated once by the truth simulator."""
    folder = (root or cache_root()) / "campaigns" / f"{_safe(case.name)}-{case.key()}"
    names = ("random_0", "random_1", "earthquake")
    paths = [folder / f"{n}.toml" for n in names]
    done = folder / "done.json"
    if done.exists() and all(p.exists() for p in paths):
        return paths
    truth.campaign(folder, case.table(), case.true_specimen(), case.declared_specimen(),
                   fs=case.fs, noise=case.noise, seed=case.seed, spans_in=SPANS_IN,
                   duration_s=RANDOM_S, quake_peak_in=QUAKE_PEAK_IN, record=case.record)
    _write_json(done, case.definition())
    return paths


def engine_fingerprint() -> str:
    """A hash of every source file of the installed vtable package (what diagnoses)."""
    import vtable

    h = hashlib.sha256()
    pkg = Path(vtable.__file__).resolve().parent
    for p in sorted(pkg.rglob("*.py")):
        h.update(str(p.relative_to(pkg)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:12]


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in name)


def _write_json(path: Path, obj) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(obj, indent=1, default=float))
    os.replace(tmp, path)


# ---------------------------------------------------------------------------------------------
# diagnosis and the rules


def diagnose_case(case: Case, root: Path | None = None, use_cache: bool = True,
                  workers: int | None = None) -> dict:
    """Generate (or reuse) the case's campaign, diagnose it with the full catalog (the
    diagnosis's `workers` processes: its default, two, or one when cases run side by side),
    judge it. Results are cached per (case, engine source)."""
    root = root or cache_root()
    rpath = _result_path(case, root)
    if use_cache and rpath.exists():
        out = json.loads(rpath.read_text())
        out["cached"] = True
        return out
    t0 = time.perf_counter()
    paths = campaign(case, root)
    t_gen = time.perf_counter() - t0
    from vtable.diagnose.engine import Diagnoser
    from vtable.runs import read_run

    runs = [read_run(p) for p in paths]
    t1, c1 = time.perf_counter(), time.process_time()
    d = Diagnoser(runs, workers=workers).diagnose()
    t_diag, c_diag = time.perf_counter() - t1, time.process_time() - c1
    first = d.rounds[0].ranking[0].effect if d.rounds and d.rounds[0].ranking else None
    out = {"case": case.definition(), "hidden": case.hidden, "outside": case.outside,
           "declared": case.declared_specimen().declared(),
           "true": case.true_specimen().declared(),
           "found": d.final_effects, "first_ranked": first,
           "start_error": d.start_error, "final_error": d.final_error,
           "noise_floor": d.noise_floor, "unexplained": d.unexplained, "verdict": d.verdict,
           "samples": int(sum(len(r.time) for r in runs)),
           "time_generate_s": t_gen, "time_s": t_diag, "cpu_s": c_diag,
           "diagnosis": d.to_json()}
    out.update(judge(case, out))
    _write_json(rpath, out)
    out["cached"] = False
    return out


def diagnose_cases(cases: list[Case], jobs: int = 1, root: Path | None = None,
                   use_cache: bool = True) -> dict[str, dict]:
    """`diagnose_case` for several cases: one after the other, each diagnosis on its own
    worker processes; or the uncached ones in `jobs` processes side by side (spawned: the
    parent may hold numba's and the engine's threads), each diagnosis then in one."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    todo = [c for c in cases if not (use_cache and _cached(c, root))]
    out = {c.name: diagnose_case(c, root) for c in cases if c not in todo}
    if len(todo) > 1 and jobs > 1:
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=min(jobs, len(todo)), mp_context=ctx) as pool:
            futs = {c.name: pool.submit(diagnose_case, c, root, use_cache, 1) for c in todo}
            out.update({n: f.result() for n, f in futs.items()})
    else:
        out.update({c.name: diagnose_case(c, root, use_cache) for c in todo})
    return out


def _result_path(case: Case, root: Path | None = None) -> Path:
    return ((root or cache_root()) / "results"
            / f"{_safe(case.name)}-{case.key(engine_fingerprint())}.json")


def _cached(case: Case, root: Path | None = None) -> bool:
    return _result_path(case, root).exists()


def judge(case: Case, r: dict) -> dict:
    """The acceptance rule for one case: {"ok": bool, "why": str}."""
    found = sorted(r["found"])
    if case.kind == "in_catalog":
        ok = found == case.hidden
        why = "" if ok else (f"found {found or 'nothing'}, hidden {case.hidden}")
    elif case.kind in ("null", "misdeclared_null"):
        ok = not found
        why = "" if ok else f"added {found} to a null case"
    else:
        ok = r["unexplained"] is not None
        extra = sorted(set(found) - set(case.hidden))
        why = ("" if ok else "unexplained is null: the final model claims to close the gap"
               + (f" with {extra}" if extra else ""))
    return {"ok": ok, "why": why}


def calibration_errors(r: dict) -> tuple[float, float]:
    """How far the calibrated base ends from the truth's specimen: (largest |relative
    error| of a mode's frequency, largest |relative error| of a mode's damping ratio: a
    building's are calibrated per mode)."""
    base, true = r["diagnosis"]["base"], r["true"]
    f_true = true.get("frequencies_hz") or [true["frequency_hz"]]
    keys = (["specimen.frequency_hz"] if "specimen.frequency_hz" in base else
            [f"specimen.mode{k}.frequency_hz" for k in range(1, len(f_true) + 1)])
    df = max(abs(base[k]["fitted"] / f - 1) for k, f in zip(keys, f_true, strict=True))
    xi = [base[k]["fitted"] for k in (["specimen.damping"] if "specimen.damping" in base else
                                      [f"specimen.mode{j}.damping"
                                       for j in range(1, len(f_true) + 1)])]
    return df, max(abs(x / true["damping"] - 1) for x in xi)


def totals(results: list[tuple[Case, dict]]) -> dict[str, Any]:
    """The acceptance's figures over the cases run."""
    by: dict[str, list[bool]] = {k: [] for k in KINDS}
    for case, r in results:
        by[case.kind].append(bool(r["ok"]))
    inc = by["in_catalog"]
    nulls = by["null"] + by["misdeclared_null"]
    frac = sum(inc) / len(inc) if inc else None
    cal = [calibration_errors(r) for c, r in results
           if c.kind in ("null", "misdeclared_null") and "diagnosis" in r]
    df = max((e[0] for e in cal), default=None)
    dxi = max((e[1] for e in cal), default=None)
    return {"in_catalog": (sum(inc), len(inc)), "in_catalog_fraction": frac,
            "null": (sum(nulls), len(nulls)), "outside": (sum(by["outside"]), len(by["outside"])),
            "calibration": {"frequency": df, "damping": dxi, "cases": len(cal)},
            "accepted": ((frac is None or frac >= 0.9) and all(nulls) and all(by["outside"])
                         and (df is None or (df <= 0.005 and dxi <= 0.20))),
            "time_s": sum(r["time_s"] for _, r in results)}
