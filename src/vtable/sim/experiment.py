"""One virtual-table test in the report's configuration, end to end: the table and the
specimen by name, the command checked against the table, `simulate`, the run files in the
interchange format (the verbs write the Rerun recording, `vtable.viz.rerun_scene.log_run`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vtable import units
from vtable.effects.registry import STANDARD_RC_FILTER
from vtable.errors import VtableError
from vtable.models.physics import Physics
from vtable.opensees.model import load_model
from vtable.params import presets
from vtable.params.base import read_toml
from vtable.params.specimen import NoSpecimen, OpenSeesSpecimen, Specimen, specimen_from_dict
from vtable.params.virtual import VirtualTable
from vtable.runs import write_run
from vtable.runs.lab import lab_table
from vtable.runs.table import table_from_dict
from vtable.signals.command import Command
from vtable.sim.run import SimulatedRun, simulate, simulation_step, standard_physics
from vtable.sim.simulator import SimResult
from vtable.tables.eerc import virtual_table


def check_playable(command: Command, vt: VirtualTable, control_dt: float,
                   output_dt: float) -> list[str]:
    """Refuse what the table or the simulation cannot play, before running: a sine above
    the table's band (Table 2.2), any content at or above the Nyquist frequency of the
    output rate (it would alias into the run file). Returns notes (a random band reaching
    beyond the table's band is played, as the report's 0-50 Hz random tests were, and
    said)."""
    band = vt.table.specs.bandwidth
    nyq = 0.5 / max(control_dt, output_dt)
    tab = command.table
    notes = []
    if tab.get("kind") == "sine":
        f = float(tab["frequency_hz"])
        if band is not None and f > band:
            raise VtableError(f"sine {f:g} Hz is above the table's 0-{band:g} Hz band "
                              f"({vt.limits_source}): the table cannot play it")
        if f >= nyq:
            raise VtableError(f"sine {f:g} Hz is at or above the Nyquist frequency {nyq:g} Hz "
                              "of the recorded channels: it would alias")
    if tab.get("kind") == "random":
        lo, hi = (float(v) for v in tab["band_hz"])
        if hi >= nyq:
            raise VtableError(f"random band {lo:g}-{hi:g} Hz reaches the Nyquist frequency "
                              f"{nyq:g} Hz of the recorded channels: it would alias")
        if band is not None and hi > band:
            notes.append(f"the random band reaches {hi:g} Hz, beyond the table's 0-{band:g} "
                         f"Hz band ({vt.limits_source}): the table attenuates it")
    return notes


def load_table(name_or_path: str | None):
    """A table preset name (eerc, lnec-st1d) or a TOML file with a run-format [table]
    table, as the models read it (`vtable.params.virtual.VirtualTable`)."""
    if name_or_path in (None, "", "eerc"):
        return lab_table(None)
    p = Path(name_or_path)
    if name_or_path.endswith(".toml") or p.is_file():
        d = read_toml(p)
        given = d.get("table", d)
        return dataclasses.replace(lab_table(table_from_dict(given, f"{p} [table]")),
                                   declared=given)
    return lab_table(table_from_dict({"preset": name_or_path}, f"--table {name_or_path}"))


def load_specimen(name_or_path: str | None) -> Specimen:
    """A specimen preset name (none, concrete_blocks, sdof_frame, table5_1, table8_1) or a
    TOML file with a run-format [specimen] table, for the verbs that step it (simulate,
    study, export-mjcf): an OpenSees model file is run (built) here."""
    if name_or_path in (None, "", "none"):
        return NoSpecimen()
    p = Path(name_or_path)
    if name_or_path.endswith(".toml") or p.is_file():
        d = read_toml(p)
        given = d.get("specimen", d)
        if isinstance(given, dict):  # a run's state says when it was made, not what it is
            given = {k: v for k, v in given.items() if k != "state"}
        spec = specimen_from_dict(given, f"{p} [specimen]", p.parent)
        if isinstance(spec, OpenSeesSpecimen):  # simulate steps it: built and checked now
            try:
                load_model(spec.model)
            except VtableError as e:
                raise VtableError(f"{p} [specimen].model: {e}") from None
        return spec
    return presets.specimen(name_or_path)


#: `--valve nonlinear`: the appendix C valve, an alias for these two effects
NONLINEAR_VALVE = ("valve_flow_nonlinearity", "flow_saturation")
#: the standard table's ΔP feedback RC filter (eq B.4), left out by `rc_filter=False`
RC_FILTER = STANDARD_RC_FILTER


def experiment_physics(specimen: Specimen, vt: VirtualTable | None = None, *,
                       valve: str = "linear", rc_filter: bool = True,
                       effects: Mapping[str, Mapping[str, float]] | None = None
                       ) -> Physics:
    """The report's configuration of `vt` carrying `specimen` as a `Physics`: the standard
    table (`standard_physics`; without its RC filter if not `rc_filter`), `effects` added;
    `valve="nonlinear"` adds `NONLINEAR_VALVE` (at their defaults unless `effects` sets
    them)."""
    if valve not in ("linear", "nonlinear"):
        raise VtableError(f"valve must be linear or nonlinear, got {valve!r}")
    extra = {k: dict(v) for k, v in (effects or {}).items()}
    if valve == "nonlinear":
        for e in NONLINEAR_VALVE:
            extra.setdefault(e, {})
    ph = standard_physics(specimen, None, vt)
    ph = ph if rc_filter else ph.without(RC_FILTER)
    for name, params in extra.items():
        ph = ph.with_effect(name, params)
    return ph


@dataclass
class Experiment:
    """A simulated test (`run`: the channels in SI, as a run file holds them, and the
    simulation behind them) and the files written."""

    run: SimulatedRun
    command: Command
    files: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    specimen: Specimen | None = None

    @property
    def result(self) -> SimResult:
        return self.run.result

    def channel(self, name: str) -> np.ndarray:
        """A channel in its run-file unit (the report's units)."""
        return units.from_si(self.run.channels[name], self.run.units[name])


def run_experiment(specimen: Specimen, command: Command, *, vt: VirtualTable | None = None,
                   valve: str = "linear", out: str | Path | None = None,
                   output_dt: float = 0.005, title: str = "", rc_filter: bool = True,
                   effects: Mapping[str, Mapping[str, float]] | None = None) -> Experiment:
    """Simulate `command` on the table carrying `specimen` (`simulate` of
    `experiment_physics`, with the full state) and write the run files to `out`."""
    vt = vt or virtual_table()
    ph = experiment_physics(specimen, vt, valve=valve, rc_filter=rc_filter, effects=effects)
    rate = 1.0 / output_dt
    dt, _ = simulation_step(ph, rate, vt)
    notes = [*command.notes, *check_playable(command, vt, dt, output_dt)]
    if isinstance(specimen, OpenSeesSpecimen):  # the one verb that runs a model file
        notes.append(f"runs {Path(specimen.model).name}, Python (its build(ops), to step the "
                     "model; the run holds the model as data, so its readers do not run it)")
    added = {k: v for k, v in ph.effects.items()
             if k not in standard_physics(specimen, None, vt).effects}
    if added:
        notes.append("effects on the standard table: " + ", ".join(
            f"{k}" + (f" ({', '.join(f'{p}={v:g}' for p, v in pv.items())})" if pv else "")
            for k, pv in added.items()))
    run = simulate(ph, command, rate, vt=vt, name=str(out or command.name), full_state=True,
                   title=title or f"{command.name}, {specimen.title} (vtable virtual table)")
    exp = Experiment(run, command, notes=notes, specimen=specimen)
    if out is not None:
        exp.files += list(write_run(exp.run, out))
    return exp
