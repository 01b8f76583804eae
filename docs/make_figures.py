"""Regenerate the figures under docs/img from a campaign made as the README shows (the SDOF
frame on Berkeley's table, random 0-25 Hz at 0.1 and 0.25 in and El Centro, 3 kip of
actuator friction hidden, 1 % sensor noise), diagnosed with the full catalog:

    python docs/make_figures.py

The campaign is cached as benchmarks/bench_readme_campaigns.py caches it."""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from readme_campaigns import campaign  # noqa: E402

from vtable import verbs  # noqa: E402
from vtable.viz.diagnosis_report import tf_overlay, time_histories  # noqa: E402


def main() -> None:
    root = Path(os.environ.get("VTABLE_README_CACHE",
                               Path.home() / ".cache" / "vtable-readme-campaigns"))
    d = verbs.diagnose(campaign("actuator_friction", 0.01, root))
    out = HERE / "img"
    out.mkdir(exist_ok=True)
    tf_overlay(d, "structure acceleration", d.runs[2]).savefig(out / "report_bode.png", dpi=90)
    time_histories(d, d.runs[2]).savefig(out / "report_time_histories.png", dpi=90)
    print(f"wrote {out / 'report_bode.png'}, {out / 'report_time_histories.png'}")


if __name__ == "__main__":
    main()
