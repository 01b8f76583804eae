"""A yielding storey on an LNEC-like table under PID, found by a plain `diagnose` (issue 31):
campaigns the independent truth simulator (tests/truth) makes on its LNEC ST1D preset with
a PID + feedforward controller (the scorecard's `lnec_pid_ff_*` table), the specimen's
storey yielding (the truth's own Bouc–Wen integration) and declared elastic and off as a
lab's would be; each diagnosed with the whole catalog, no flags.

A case is right when the final set is exactly {storey_yield} on the storey that yields,
its yield drift within 20 % of the truth's, and the final error within 2x the noise floor.

    python benchmarks/bench_yield_lnec.py [--fresh]

Campaigns and results are cached like the scorecard's (tests/scorecard.py)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import scorecard as sc
import truth


def cases() -> list[tuple[sc.Case18, int, float]]:
    """(case, yielding storey, yield drift in): the scorecard's LNEC PID table, its pink-
    noise runs at 0.2 and 0.6 in peak and a synthetic earthquake; the 2 t SDOF (8.3 Hz)
    and the 3-storey LNEC building (4, 11, 16 Hz), declared within the calibration bounds."""
    table = sc.BY_NAME_18["lnec_pid_ff_null"].table
    cmds = sc.BY_NAME_18["lnec_pid_ff_null"].commands
    out = []
    for k, (name, spec, storey, u_y, alpha) in enumerate((
            ("lnec_pid_yield_sdof", "sdof", 1, 0.4, 0.05),
            ("lnec_pid_yield_sdof_soft", "sdof", 1, 0.25, 0.1),
            ("lnec_pid_yield_3storey_s1", "3storey", 1, 0.25, 0.05))):
        h = {"yield_drift_in": u_y, "post_yield_ratio": alpha}
        if spec == "sdof":
            true = truth.sdof(4.4, 40.0, 8.3, 0.02, hysteresis=h)
            elastic = truth.sdof(4.4, 40.0, 8.3, 0.02)
            declared = truth.perturb(elastic, seed=3100 + k)
        else:
            h["storeys"] = [storey]
            kw = dict(frequencies_hz=[4.0, 11.0, 16.0], rayleigh=((4.0, 0.02), (16.0, 0.04)))
            true = truth.building([1.5, 1.5, 1.5], [30.0, 60.0, 90.0], hysteresis=h, **kw)
            elastic = truth.building([1.5, 1.5, 1.5], [30.0, 60.0, 90.0], **kw)
            declared = truth.perturb(elastic, seed=3100 + k, frequency=0.0225, damping=1.5,
                                     weight=0.05)
        case = sc.Case18(name, "in_catalog", table, true, declared, cmds, ("storey_yield",),
                         seed=310 + k)
        out.append((case, storey, u_y))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fresh", action="store_true", help="ignore cached results")
    a = ap.parse_args(argv)
    right = 0
    all_cases = cases()
    for case, storey, u_y in all_cases:
        r = sc.diagnose_case(case, use_cache=not a.fresh)
        p = r.get("storey_yield") or {}
        ratio = r["final_error"] / r["noise_floor"]
        why = []
        if sorted(r["found"]) != ["storey_yield"]:
            why.append(f"found {r['found'] or 'nothing'}")
        if p and sc.yielding_storeys(p) != [storey]:
            why.append(f"storeys {sc.yielding_storeys(p)}, the truth's {storey}")
        if p and abs(p["yield_drift"] / u_y - 1) > 0.2:
            why.append(f"yield drift {p['yield_drift']:.3g} in, the truth's {u_y:g}")
        if ratio > 2.0:
            why.append(f"final {ratio:.1f}x the floor")
        right += not why
        fitted = (f"storeys {','.join(map(str, sc.yielding_storeys(p)))} at "
                  f"{p['yield_drift']:.3g} in (truth {u_y:g}), "
                  f"post-yield {p['post_yield_ratio']:.3g}" if p else "no storey_yield")
        print(f"{case.name:<28} {fitted:<50} start {r['start_error']:6.2%} final "
              f"{r['final_error']:6.2%} floor {r['noise_floor']:6.2%} ({ratio:.1f}x) "
              f"{r['time_s']:4.0f}s  {'yes' if not why else 'NO: ' + '; '.join(why)}"
              + (" (cached)" if r.get("cached") else ""), flush=True)
    print(f"right in {right}/{len(all_cases)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
