"""The diagnosis scorecard (issue 12): 40 cases whose campaigns the independent truth
simulator (tests/truth) makes with a hidden truth and a perturbed declaration, each
diagnosed with the full catalog; one line per case and the acceptance totals.

    python benchmarks/bench_diagnosis_scorecard.py                  # all 40 cases
    python benchmarks/bench_diagnosis_scorecard.py --quick          # 3 cases, one per kind
    python benchmarks/bench_diagnosis_scorecard.py --cases backlash_1,null_sdof_elcentro
    python benchmarks/bench_diagnosis_scorecard.py --list

Campaigns and results are cached under $VTABLE_SCORECARD_CACHE (default
~/.cache/vtable-scorecard; results are keyed by the case and the vtable source, so a changed
engine is diagnosed again; `--fresh` ignores cached results). `--json FILE` writes every
result. Case definitions and rules: tests/scorecard.py.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import scorecard as sc

HEAD = (f"{'case':<30} {'kind':<8} {'truth':<44} {'found':<56} {'first-ranked':<24} "
        f"{'start':>6} {'final':>6} {'floor':>6} {'ratio':>5} {'time':>6}  ok")


def _short(kind: str) -> str:
    return {"in_catalog": "in", "null": "null", "misdeclared_null": "misdecl",
            "outside": "outside"}[kind]


def _truth(case: sc.Case) -> str:
    parts = []
    for name, p in case.effects.items():
        vals = ",".join(f"{v:g}" for v in p.values())
        parts.append(f"{name}({vals})" if vals else name)
    return "+".join(parts) or "-"


def line(case: sc.Case, r: dict) -> str:
    u = r["unexplained"]
    ratio = f"{u['ratio_to_floor']:.1f}" if u else "-"
    found = ",".join(r["found"]) or "-"
    return (f"{case.name:<30} {_short(case.kind):<8} {_truth(case):<44.44} {found:<56.56} "
            f"{(r['first_ranked'] or '-'):<24.24} {r['start_error']:6.2%} "
            f"{r['final_error']:6.2%} {r['noise_floor']:6.2%} {ratio:>5} "
            f"{r['time_s']:5.0f}s  {'yes' if r['ok'] else 'NO: ' + r['why']}"
            + (" (cached)" if r.get("cached") else ""))


def _run(name: str, fresh: bool, workers: int | None = None) -> tuple[str, dict]:
    return name, sc.diagnose_case(sc.BY_NAME[name], use_cache=not fresh, workers=workers)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", help="comma-separated case names (default: all)")
    ap.add_argument("--quick", action="store_true", help=f"the cases {', '.join(sc.QUICK)}")
    ap.add_argument("-j", "--jobs", type=int, default=1,
                    help="cases side by side (default 1: one at a time, each diagnosis on its "
                         "two worker processes, so each case's time is a diagnosis's own)")
    ap.add_argument("--fresh", action="store_true", help="ignore cached results")
    ap.add_argument("--json", help="write every result to this file")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    a = ap.parse_args(argv)
    if a.list:
        for c in sc.CASES:
            print(f"{c.name:<30} {_short(c.kind):<8} {c.specimen:<8} {c.pitch:<15} "
                  f"com {c.com_height_in:4.1f} in  {c.fs:5g} Hz  noise {c.noise:.0%}  "
                  f"{c.record:<9} seed {c.seed}  {_truth(c)}")
        return 0
    names = [c.name for c in sc.CASES]
    if a.quick:
        names = list(sc.QUICK)
    if a.cases:
        names = [n.strip() for n in a.cases.split(",") if n.strip()]
        bad = [n for n in names if n not in sc.BY_NAME]
        if bad:
            print(f"unknown case(s) {', '.join(bad)}; --list shows them", file=sys.stderr)
            return 2
    print(f"diagnosis scorecard: {len(names)} case(s), {a.jobs} process(es), cache "
          f"{sc.cache_root()}, engine {sc.engine_fingerprint()}")
    print(HEAD)
    t0 = time.perf_counter()
    results: dict[str, dict] = {}
    if a.jobs > 1:
        with ProcessPoolExecutor(max_workers=a.jobs) as pool:
            futs = [pool.submit(_run, n, a.fresh, 1) for n in names]
            for f in as_completed(futs):
                n, r = f.result()
                results[n] = r
                print(line(sc.BY_NAME[n], r), flush=True)
    else:
        for n in names:
            _, r = _run(n, a.fresh)
            results[n] = r
            print(line(sc.BY_NAME[n], r), flush=True)
    wall = time.perf_counter() - t0
    done = [(sc.BY_NAME[n], results[n]) for n in names]
    tot = sc.totals(done)

    def frac(p):
        return f"{p[0]}/{p[1]}" if p[1] else "none run"

    print()
    fr = tot["in_catalog_fraction"]
    print(f"in-catalog: exact hidden set in {frac(tot['in_catalog'])}"
          + (f" ({fr:.0%}; acceptance >= 90 %)" if fr is not None else ""))
    print(f"null and mis-declared null: nothing added in {frac(tot['null'])} (acceptance: all)")
    print(f"outside the catalog: unexplained not null in {frac(tot['outside'])} "
          "(acceptance: all)")
    cal = tot["calibration"]
    if cal["cases"]:
        print(f"calibrated base on the {cal['cases']} null cases: every mode frequency within "
              f"{cal['frequency']:.2%} of the truth (acceptance 0.5 %), damping within "
              f"{cal['damping']:.1%} (acceptance 20 %)")
    n_new = sum(not r.get("cached") for _, r in done)
    per = tot["time_s"] / len(done) if done else 0.0
    print(f"diagnosis time: {tot['time_s']:.0f} s in all, {per:.0f} s per case "
          f"({n_new} diagnosed now, {len(done) - n_new} from the cache); wall {wall:.0f} s")
    print("acceptance on these cases: " + ("MET" if tot["accepted"] else "NOT MET"))
    if a.json:
        Path(a.json).write_text(json.dumps({"totals": tot, "results": results}, indent=1,
                                           default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
