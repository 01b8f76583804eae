"""The one way to simulate the virtual table: `simulate(physics, command, rate) -> Run`.

A `Physics` (the base loop, the specimen, the effects) is realised on the multibody table
by `vtable.models.virtual.VirtualAssembly` (`setup`), stepped by `Simulator` at the largest
step the stiff elements allow that divides the output period, turned into the run format's
channels (`channels.result_run`), passed once through the effects' output filters at the
simulation rate, sampled at `rate` and, if asked, given sensor noise. The CLI's `simulate`
and `demo`, the studies, the tests and the diagnosis's virtual-table checks all come here.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping

import numpy as np

from vtable.effects.registry import STANDARD
from vtable.errors import VtableError
from vtable.mjcf.builder import BuiltModel
from vtable.models import physics as phys
from vtable.models.virtual import MAX_STEP, VirtualAssembly
from vtable.opensees.equivalent import realised
from vtable.params.specimen import OpenSeesSpecimen, Specimen
from vtable.params.virtual import VirtualTable
from vtable.runs import specimen_table
from vtable.runs.model import COMMAND_CHANNELS, Run, with_noise
from vtable.signals.command import Command
from vtable.sim.channels import result_run
from vtable.sim.simulator import SimResult, Simulator
from vtable.tables.eerc import virtual_table

#: Hz: the rate of the runs the diagnosis tests are made of
OUTPUT_FS = 200.0


@dataclasses.dataclass
class SimulatedRun(Run):
    """A simulated run: the channels (SI, at the output rate) and `result`, the simulation's
    histories at the same instants (joints, sensors, limit exceedances) behind them."""

    result: SimResult | None = None

    def __getstate__(self) -> dict:
        """A pickled copy (a diagnosis's worker processes) holds the run, not the
        simulation (MuJoCo's model does not pickle)."""
        return {**self.__dict__, "result": None}

    @property
    def built(self) -> BuiltModel:
        return self.result.built


def standard_physics(specimen: Specimen, extra: Mapping[str, Mapping[str, float]] | None = None,
                     vt: VirtualTable | None = None) -> phys.Physics:
    """The standard virtual table `vt` (EERC by default) as a `Physics`: its own loop
    (eq 6.16 from its servo constants) and the standard effects (`registry.STANDARD`: the
    pitch system, the ΔP feedback's RC filter) that the table can realise (a table whose
    platen does not pitch refuses the pitch system), plus `extra` effects."""
    vt = vt or virtual_table()
    base = phys.nominal_open_loop(vt)
    std = {}
    for name in STANDARD:
        trial = phys.Physics(base, specimen, {name: {}})
        try:
            trial.apply(VirtualAssembly(trial, vt), "virtual")
        except VtableError:
            continue
        std[name] = {}
    return phys.Physics(base, specimen, {**std, **{k: dict(v) for k, v in (extra or {}).items()}})


def setup(ph: phys.Physics, vt: VirtualTable | None = None, timestep: float = MAX_STEP
          ) -> tuple[BuiltModel, list, list[tuple[Callable, frozenset | None]]]:
    """(built model, controllers, output filters) realising `ph` on `vt` at `timestep`."""
    va = VirtualAssembly(ph, vt or virtual_table(), timestep)
    ph.apply(va, "virtual")
    if va.max_step < timestep:
        raise VtableError(f"a stiff force element needs a step of {va.max_step:.3g} s or "
                          f"less, not {timestep:g} s")
    built, ctl = va.finalize()
    return built, ctl, va.filters


def max_step(ph: phys.Physics, vt: VirtualTable | None = None) -> float:
    """The largest step the virtual table realising `ph` may take (stiff elements)."""
    va = VirtualAssembly(ph, vt or virtual_table())
    ph.apply(va, "virtual")
    return va.max_step


def simulation_step(ph: phys.Physics, rate: float, vt: VirtualTable | None = None
                    ) -> tuple[float, int]:
    """(dt, k): the step 1/(k·rate), k = ⌈1/(max step · rate)⌉ (1 ms at 200 Hz and 1 kHz,
    1/1024 s at 256 Hz), and the k steps per output sample."""
    if not (np.isfinite(rate) and rate > 0):
        raise VtableError(f"output rate {rate:g} Hz: expected a positive rate")
    k = max(1, math.ceil(1.0 / (max_step(ph, vt) * rate) - 1e-9))
    return 1.0 / (k * rate), k


def simulate(physics: phys.Physics, command: Command, rate: float = OUTPUT_FS, *,
             vt: VirtualTable | None = None, noise: float = 0.0, seed: int = 0,
             name: str = "", title: str = "", full_state: bool = False,
             check: bool = True) -> SimulatedRun:
    """Simulate `command` on the virtual table realising `physics`.

    Parameters
    ----------
    physics
        The base loop, the specimen and the effects (`standard_physics` gives the
        standard table's).
    command
        The horizontal displacement command (`vtable.signals.make_command`).
    rate
        Output rate, Hz (200 by default). The table is stepped at 1/(k·rate)
        (`simulation_step`); every k-th sample is kept, after the effects' output filters,
        which act once, at the simulation rate.
    vt
        The virtual table (the EERC table by default; `vtable.runs.lab.lab_table` a lab's).
    noise, seed
        White sensor noise, as a fraction of each channel's RMS (command channels clean).
    name, title
        The run's name (the command's by default) and its meta title.
    full_state
        Add the joints' and controllers' states as extra ``state_*`` channels.
    check
        Refuse commands beyond the table's stroke or velocity (Table 2.2).

    Returns
    -------
    SimulatedRun
        A `Run` (channels in SI at `rate`) with `.result`, the simulation's histories.
    """
    vt = vt or virtual_table()
    dt, k = simulation_step(physics, rate, vt)
    built, ctl, filters = setup(physics, vt, dt)
    res = Simulator(built, ctl).run(command.t, {"x": command.x},
                                    output_dt=dt if filters else k * dt, check=check)
    spec = physics.specimen
    if isinstance(spec, OpenSeesSpecimen) and spec.building is None:
        spec, _ = realised(spec, vt.pivot_depth)  # the model as data, for the run's readers
    meta = {"title": title or f"{command.name}, {physics.specimen.title} (vtable virtual "
                              f"table: {physics.label})",
            "table": declared_table(built.vt),
            **({"control": {d: s.to_dict() for d, s in vt.settings.items()}} if vt.knobs
               else {}),
            "specimen": specimen_table(spec), "command": command.table}
    run = result_run(res, meta, name or command.name, full_state=full_state)
    for fn, only in filters:  # the effects' output filters, once, on measured channels
        run.channels = {c: v if c in COMMAND_CHANNELS or c.startswith("state_")
                        or (only is not None and c not in only)
                        else fn(v, 1.0 / dt) for c, v in run.channels.items()}
    if filters:
        run.channels = {c: v[::k] for c, v in run.channels.items()}
        res = every(res, k)
    run.time = np.arange(len(res.t)) / rate
    run.reports.append(f"virtual table: {physics.label}, sampled at {rate:g} Hz")
    out = SimulatedRun(**{f.name: getattr(run, f.name) for f in dataclasses.fields(Run)},
                       result=res)
    return with_noise(out, noise, seed) if noise else out


def declared_table(vt) -> dict:
    """The run-format [table] a run made on `vt` writes: its declaration (a preset's name
    when it has none) with what its force channels measured (`force_measured`: the
    virtual table knows, so its runs say it)."""
    d = dict(vt.declared or {"preset": vt.name})
    d["horizontal"] = {**d.get("horizontal", {}), "force_measured": vt.force_measured}
    return d


def every(res: SimResult, k: int) -> SimResult:
    """Every k-th recorded sample of `res` (the same as recording at k times the step)."""
    sub = {f.name: getattr(res, f.name)[::k] for f in dataclasses.fields(SimResult)
           if isinstance(getattr(res, f.name), np.ndarray)}
    if res.specimen is not None:
        sub["specimen"] = {name: v[::k] for name, v in res.specimen.items()}
    return dataclasses.replace(res, **sub)
