"""The diagnosis scorecard (issue 12): 40 cases whose campaigns the independent truth
simulator (tests/truth) makes with a hidden truth and a perturbed declaration, each
diagnosed with the full catalog; one line per case and the acceptance totals.

    python benchmarks/bench_diagnosis_scorecard.py                  # all 40 cases
    python benchmarks/bench_diagnosis_scorecard.py --quick          # 3 cases, one per kind
    python benchmarks/bench_diagnosis_scorecard.py --cases backlash_1,null_sdof_elcentro
    python benchmarks/bench_diagnosis_scorecard.py --list
    python benchmarks/bench_diagnosis_scorecard.py --set 18         # issue 18's 32 cases
    python benchmarks/bench_diagnosis_scorecard.py --set all        # all three (88 cases)
    python benchmarks/bench_diagnosis_scorecard.py --set 21         # issue 21's yielding set

Campaigns and results are cached under $VTABLE_SCORECARD_CACHE (default
~/.cache/vtable-scorecard; results are keyed by the case and the vtable source, so a changed
engine is diagnosed again; `--fresh` ignores cached results). `--json FILE` writes every
result. Case definitions and rules: tests/scorecard.py (issue 18's: CASES_18, judge18:
the exact effect set; "unexplained" said by the verdict; every suspect declaration named in
base_at_bounds and the verdict; a campaign vtable refuses fails with its refusal).
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


HEAD_18 = (f"{'case (issue 18)':<38} {'kind':<13} {'expected':<34} {'found':<40} "
           f"{'final / floor':>15} {'time':>6}  ok")


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
    if isinstance(case, sc.Case21) and r.get("storey_yield"):
        p = r["storey_yield"]
        storeys = ",".join(map(str, sc.yielding_storeys(p)))
        found = found.replace("storey_yield", f"storey_yield(s{storeys},"
                              f"{p['yield_drift']:.3g}in,{p['post_yield_ratio']:.2g})")
    truth_ = _truth(case)
    if isinstance(case, sc.Case21) and case.yielding:
        h = case.yielding
        truth_ = "+".join(x for x in (f"yield(s{','.join(map(str, sc.expected_storeys(case)))},"
                                      f"{h['yield_drift_in']:g}in,{h['post_yield_ratio']:g})",
                                      _truth(case)) if x != "-")
    return (f"{case.name:<30} {_short(case.kind):<8} {truth_:<44.44} {found:<56.56} "
            f"{(r['first_ranked'] or '-'):<24.24} {r['start_error']:6.2%} "
            f"{r['final_error']:6.2%} {r['noise_floor']:6.2%} {ratio:>5} "
            f"{r['time_s']:5.0f}s  {'yes' if r['ok'] else 'NO: ' + r['why']}"
            + (" (cached)" if r.get("cached") else ""))


def _case(name: str) -> sc.Case | sc.Case18:
    for by in (sc.BY_NAME, sc.BY_NAME_18, sc.BY_NAME_21, sc.BY_NAME_32):
        if name in by:
            return by[name]
    raise KeyError(name)


def _expected(case: sc.Case18) -> str:
    if case.expected == sc.SUSPECT:
        return "suspect " + ",".join(case.suspect)
    return case.expected if isinstance(case.expected, str) else ",".join(case.expected) or "-"


def line18(case: sc.Case18, r: dict) -> str:
    """One issue-18 case: expected, found, final error / floor, time, ok or why."""
    found = ",".join(r["found"]) or "-"
    if r.get("refused"):
        errs = f"{'refused':>15}"
    else:
        errs = f"{r['final_error']:6.2%} / {r['noise_floor']:6.2%}"
    return (f"{case.name:<38} {case.kind:<13} {_expected(case):<34.34} {found:<40.40} "
            f"{errs} {r['time_s']:5.0f}s  {'yes' if r['ok'] else 'NO: ' + r['why']}"
            + (" (cached)" if r.get("cached") else ""))


def _line(name: str, r: dict) -> str:
    c = _case(name)
    return line18(c, r) if isinstance(c, sc.Case18) else line(c, r)


def _run(name: str, fresh: bool, workers: int | None = None) -> tuple[str, dict]:
    return name, sc.diagnose_case(_case(name), use_cache=not fresh, workers=workers)


def _frac(p: tuple[int, int]) -> str:
    return f"{p[0]}/{p[1]}" if p[1] else "none run"


def _totals12(tot: dict) -> None:
    """Issue 12's acceptance figures."""
    fr = tot["in_catalog_fraction"]
    print(f"in-catalog: exact hidden set in {_frac(tot['in_catalog'])}"
          + (f" ({fr:.0%}; acceptance >= 90 %)" if fr is not None else ""))
    print(f"null and mis-declared null: nothing added in {_frac(tot['null'])} "
          "(acceptance: all)")
    print(f"outside the catalog: unexplained not null in {_frac(tot['outside'])} "
          "(acceptance: all)")
    cal = tot["calibration"]
    if cal["cases"]:
        print(f"calibrated base on the {cal['cases']} null cases: every mode frequency within "
              f"{cal['frequency']:.2%} of the truth (acceptance 0.5 %), damping within "
              f"{cal['damping']:.1%} (acceptance 20 %)")


def _totals18(tot: dict) -> None:
    """Issue 18's acceptance figures."""
    fr = tot["exact_fraction"]
    print(f"issue 18: right in {_frac(tot['exact'])}"
          + (f" ({fr:.0%}; acceptance >= 95 %)" if fr is not None else ""))
    fp = tot["false_positives"]
    print(f"false positives (added in a null or beyond-bounds case): {len(fp)}"
          + (" (" + "; ".join(f"{k}: {','.join(v)}" for k, v in fp.items()) + ")" if fp else "")
          + " (acceptance: 0)")
    print(f"outside the catalog: unexplained in {_frac(tot['unexplained'])}; beyond the "
          f"bounds: right in {_frac(tot['suspect'])} (acceptance: all; the suspect named, "
          f"whatever was added: {_frac(tot['suspect_named'])})")
    if tot["refused"]:
        print(f"refused by vtable: {', '.join(tot['refused'])}")


def _combined(done: list, done18: list, tot: dict, tot18: dict) -> bool:
    """Issue 18's acceptance on the whole scorecard (issue 12's cases and its own): >= 95 %
    right, no effect added in a null or beyond-bounds case, every outside-catalog case
    unexplained, every beyond-bounds case right."""
    right = sum(bool(r["ok"]) for _, r in done) + tot18["exact"][0]
    n = len(done) + len(done18)
    fp = [c.name for c, r in done if c.kind in ("null", "misdeclared_null") and r["found"]]
    fp += list(tot18["false_positives"])
    out_ok = tot["outside"][0] + tot18["unexplained"][0]
    out_n = tot["outside"][1] + tot18["unexplained"][1]
    met = right >= 0.95 * n and not fp and out_ok == out_n and all(
        bool(r["ok"]) for c, r in done18 if c.kind == "beyond_bounds")
    print(f"the whole scorecard ({n} cases; issue 18's acceptance): right in {right}/{n} "
          f"({right / n:.1%}; acceptance >= 95 %), false positives {len(fp)}, outside the "
          f"catalog unexplained in {out_ok}/{out_n}, beyond the bounds right in "
          f"{_frac(tot18['suspect'])}: " + ("MET" if met else "NOT MET"))
    return met


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
    ap.add_argument("--set", choices=("12", "18", "21", "32", "all"), default="12",
                    help="issue 12's 40 cases (default), issue 18's 32, issue 21's yielding "
                         "set, issue 32's (degradation, mount, two states), or 12, 18 and "
                         "21 (all)")
    a = ap.parse_args(argv)
    if a.list:
        for c in sc.CASES if a.set in ("12", "all") else []:
            print(f"{c.name:<30} {_short(c.kind):<8} {c.specimen:<8} {c.pitch:<15} "
                  f"com {c.com_height_in:4.1f} in  {c.fs:5g} Hz  noise {c.noise:.0%}  "
                  f"{c.record:<9} seed {c.seed}  {_truth(c)}")
        for c in sc.CASES_18 if a.set in ("18", "all") else []:
            ctl = c.table.law.kind if c.table.declare_controller else "preset"
            print(f"{c.name:<38} {c.kind:<13} {c.table.preset:<9} {ctl:<14} "
                  f"{c.specimen.kind:<14} {c.fs:5g} Hz  noise {c.noise:.0%}  seed {c.seed}  "
                  f"{_expected(c)}")
        return 0
    names = ([c.name for c in sc.CASES] if a.set in ("12", "all") else []) + (
        [c.name for c in sc.CASES_18] if a.set in ("18", "all") else []) + (
        [c.name for c in sc.CASES_21] if a.set in ("21", "all") else []) + (
        [c.name for c in sc.CASES_32] if a.set == "32" else [])
    if a.quick:
        names = list(sc.QUICK)
    if a.cases:
        names = [n.strip() for n in a.cases.split(",") if n.strip()]
        bad = [n for n in names if n not in sc.BY_NAME and n not in sc.BY_NAME_18
               and n not in sc.BY_NAME_21 and n not in sc.BY_NAME_32]
        if bad:
            print(f"unknown case(s) {', '.join(bad)}; --list shows them", file=sys.stderr)
            return 2
    print(f"diagnosis scorecard: {len(names)} case(s), {a.jobs} process(es), cache "
          f"{sc.cache_root()}, engine {sc.engine_fingerprint()}")
    if any(n in sc.BY_NAME or n in sc.BY_NAME_21 for n in names):
        print(HEAD)
    if any(n in sc.BY_NAME_18 for n in names):
        print(HEAD_18)
    t0 = time.perf_counter()
    results: dict[str, dict] = {}
    if a.jobs > 1:
        with ProcessPoolExecutor(max_workers=a.jobs) as pool:
            futs = [pool.submit(_run, n, a.fresh, 1) for n in names]
            for f in as_completed(futs):
                n, r = f.result()
                results[n] = r
                print(_line(n, r), flush=True)
    else:
        for n in names:
            _, r = _run(n, a.fresh)
            results[n] = r
            print(_line(n, r), flush=True)
    wall = time.perf_counter() - t0
    done_all = [(_case(n), results[n]) for n in names]
    done21 = [(c, r) for c, r in done_all if isinstance(c, sc.Case21)]
    done = [(c, r) for c, r in done_all if isinstance(c, sc.Case) and not isinstance(c, sc.Case21)]
    done18 = [(c, r) for c, r in done_all
              if isinstance(c, sc.Case18) and not isinstance(c, sc.Case32)]
    done32 = [(c, r) for c, r in done_all if isinstance(c, sc.Case32)]
    tot = sc.totals(done)
    tot18 = sc.totals18(done18)

    print()
    if done:
        _totals12(tot)
    if done18:
        _totals18(tot18)
    tot21 = sc.totals21(done21)
    if done21:
        fr = tot21["yielding_fraction"]
        print(f"issue 21: yielding storey and yield drift right in {_frac(tot21['yielding'])}"
              + (f" ({fr:.0%}; acceptance >= 90 %)" if fr is not None else ""))
        print(f"  elastic cases right with storey_yield in the catalog: "
              f"{_frac(tot21['elastic'])}; a false storey_yield in "
              f"{tot21['false_storey_yield'] or 'none'} (acceptance: none)")
        print(f"  outside the catalog, unexplained: {_frac(tot21['outside'])} "
              "(acceptance: all)")
    tot32 = sc.totals32(done32)
    if done32:
        for kind, k in tot32.items():
            if kind == "time_s":
                continue
            print(f"issue 32, {kind}: right in {k['right']}/{k['of']} "
                  f"({k['right'] / k['of']:.0%}; acceptance >= 90 % of >= 12); beyond the "
                  f"truth: {'; '.join(k['false_positives']) or 'nothing'}")
    n_new = sum(not r.get("cached") for _, r in done_all)
    t_all = sum(r["time_s"] for _, r in done_all)
    per = t_all / len(done_all) if done_all else 0.0
    print(f"diagnosis time: {t_all:.0f} s in all, {per:.0f} s per case "
          f"({n_new} diagnosed now, {len(done_all) - n_new} from the cache); wall {wall:.0f} s")
    met = ((not done or tot["accepted"]) and (not done18 or tot18["accepted"])
           and (not done21 or tot21["accepted"])
           and all(k["right"] >= 0.9 * k["of"] and not k["false_positives"]
                   for kind, k in tot32.items() if kind != "time_s"))
    print("acceptance on these cases: " + ("MET" if met else "NOT MET")
          + (" (issue 18's set alone; the whole scorecard below)" if done and done18 else ""))
    if done and done18:
        _combined(done, done18, tot, tot18)
    if a.json:
        Path(a.json).write_text(json.dumps({"totals": tot, "totals_18": tot18,
                                            "totals_21": tot21, "totals_32": tot32,
                                            "results": results}, indent=1,
                                           default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
