"""Issue 20's acceptance figures on the independent truth simulator (tests/truth), every
case and every baseline played on the truth itself (the tests assert the main ones):
the Table 9.2 frame with pitch and a 3-storey building, El Centro (2 in) and a synthetic
Kanai-Tajimi record (2 in), declarations off; the effective motion's NRMS and the worst
error of its 5 %-damped PSA over 0.5-20 Hz on the first lab run, after one --update, and
for the three baselines; then 3 kip of friction the model lacks.

    python benchmarks/drive_acceptance.py"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import test_drive as td
import truth


def on_truth(case: str, drive, n_target: int):
    """The truth's effective motion under `drive` (m, 200 Hz)."""
    import numpy as np

    table_kw, spec, _ = td.CASES[case]
    t = np.arange(len(drive)) / td.FS
    res = truth.simulate(truth.eerc_table(**table_kw), spec,
                         truth.Command(t, drive, "drive"), fs=td.FS)
    return res.internal["x_t"] + td.effective_height(spec) * res.internal["theta"]


def main() -> None:
    from vtable.diagnose.model import TableModel
    from vtable.drive import compensate, read_target
    from vtable.ident.drive import align
    from vtable.runs import campaign

    for case in ("sdof", "building", "friction"):
        folder, paths = td.setup(case)
        runs = [align(r) for r in campaign(paths)]
        model = TableModel([td.CASES[case][2]]).fit(runs)
        for record in (("elcentro", "synthetic") if case != "friction" else ("elcentro",)):
            T = td.target(record)
            tgt = read_target("elcentro", peak=2.0) if record == "elcentro" else \
                read_target(td.synthetic_target(folder))
            r = compensate(model, tgt)
            line = [f"{case:9s} {record:9s}"]
            for p in (r.drive, *r.baselines):
                y = on_truth(case, p.drive, len(T))
                if p.name == "time-scale elongation":
                    line.append(f"elongation x{p.metrics.get('time_scale', float('nan')):.3f}")
                    continue
                line.append(f"{p.name}: NRMS {100 * td.nrms(y, T):.2f} %, PSA "
                            f"{100 * td.spectrum_error(y, T):.1f} %")
            _, _, _, run = td.drive(case, record)
            _, _, x1, _ = td.drive(case, record, update=run)
            line.append(f"after one --update: NRMS {100 * td.nrms(x1, T):.2f} %, PSA "
                        f"{100 * td.spectrum_error(x1, T):.1f} %")
            print(" | ".join(line), flush=True)


if __name__ == "__main__":
    main()
