"""One virtual-table test, end to end: a command, the simulation, the run files in the
interchange format and (optionally) the Rerun recording."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from vtable import units
from vtable.controllers import nonlinear_controllers, standard_controllers
from vtable.errors import VtableError
from vtable.mjcf import build
from vtable.params import presets
from vtable.params.base import read_toml
from vtable.params.specimen import NoSpecimen, Specimen, specimen_from_dict
from vtable.params.virtual import VirtualTable, virtual_table
from vtable.runs import FORMAT_UNITS, Run, specimen_table, write_run
from vtable.signals import band_limited_random, load_record, process_record, pulse, sine
from vtable.sim.channels import result_run
from vtable.sim.simulator import SimResult, Simulator

COMMAND_DT = 0.001


@dataclass(frozen=True)
class Command:
    """A horizontal displacement command (SI) and its run-format [command] table."""

    name: str
    t: np.ndarray
    x: np.ndarray
    table: dict[str, Any]


def make_command(kind: str = "random", *, duration: float = 11.0,
                 band: tuple[float, float] = (0.0, 25.0), peak_in: float | None = None,
                 frequency: float = 2.0, seed: int = 0, record: str | None = None,
                 length_scale: float = 3.2801) -> Command:
    """random (band-limited, §3.2), sine, pulse or earthquake (§9.2 processing of the
    record named as `load_record` takes it: elcentro, a .AT2 or .csv file, fema:ID);
    `peak_in` is the peak displacement."""
    if kind == "random":
        peak = units.to_si(peak_in if peak_in is not None else 0.25, "in")
        t, x = band_limited_random(duration, COMMAND_DT, band, peak=peak, seed=seed)
        return Command(f"random {band[0]:g}-{band[1]:g} Hz", t, x,
                       {"kind": "random", "band_hz": list(band), "peak_in": units.from_si(
                           peak, "in"), "seed": seed})
    if kind == "sine":
        amp = units.to_si(peak_in if peak_in is not None else 0.1, "in")
        t, x = sine(duration, COMMAND_DT, frequency, amp, ramp=min(1.0, duration / 4))
        return Command(f"sine {frequency:g} Hz", t, x,
                       {"kind": "sine", "frequency_hz": frequency,
                        "peak_in": units.from_si(amp, "in")})
    if kind == "pulse":
        amp = units.to_si(peak_in if peak_in is not None else 1.0, "in")
        t, x = pulse(duration, COMMAND_DT, width=1.0, amplitude=amp, start=0.5)
        return Command("pulse", t, x, {"kind": "pulse", "peak_in": units.from_si(amp, "in")})
    if kind == "earthquake":
        rec = load_record(record)
        peak = units.to_si(peak_in if peak_in is not None else 4.0, "in")
        cmd = process_record(rec, length_scale=length_scale, peak_displacement=peak)
        t_new = np.arange(0.0, cmd.time[-1] + 1e-12, COMMAND_DT)
        x = np.interp(t_new, cmd.time, cmd.displacement)
        return Command(f"{rec.name}", t_new, x,
                       {"kind": "earthquake", "record": rec.name,
                        "length_scale": length_scale, "time_scale": float(np.sqrt(length_scale)),
                        "peak_in": units.from_si(peak, "in")})
    raise VtableError(f"unknown command kind {kind!r}; expected random, sine, pulse or "
                      "earthquake")


def load_specimen(name_or_path: str | None) -> Specimen:
    """A specimen preset name (none, concrete_blocks, sdof_frame, table5_1, table8_1) or a
    TOML file with a run-format [specimen] table."""
    if name_or_path in (None, "", "none"):
        return NoSpecimen()
    p = Path(name_or_path)
    if name_or_path.endswith(".toml") or p.is_file():
        d = read_toml(p)
        return specimen_from_dict(d.get("specimen", d), f"{p} [specimen]")
    return presets.specimen(name_or_path)


@dataclass
class Experiment:
    """A simulated test (`run`: the channels in SI, as a run file holds them) and where
    its outputs went."""

    result: SimResult
    run: Run
    command: Command
    files: list[Path] = field(default_factory=list)

    def channel(self, name: str) -> np.ndarray:
        """A channel in its run-file unit (the report's units)."""
        return units.from_si(self.run.channels[name], self.run.units[name])


def run_experiment(specimen: Specimen, command: Command, *, vt: VirtualTable | None = None,
                   valve: str = "linear", out: str | Path | None = None,
                   rerun: str | Path | None = None, exaggeration: float = 50.0,
                   output_dt: float = 0.005, title: str = "",
                   rc_filter: bool = True) -> Experiment:
    """Simulate `command` on the table carrying `specimen`; write the run and the .rrd."""
    vt = vt or virtual_table()
    if valve not in ("linear", "nonlinear"):
        raise VtableError(f"valve must be linear or nonlinear, got {valve!r}")
    built = build(vt, specimen)
    if valve == "linear":
        ctl = standard_controllers(vt, rc_filter=("x", "twist") if rc_filter else ())
    else:
        ctl = nonlinear_controllers(vt)
    res = Simulator(built, ctl).run(command.t, {"x": command.x}, output_dt=output_dt)
    meta = {"title": title or f"{command.name}, {specimen.title} (vtable virtual table)",
            "table": {"preset": "eerc"},
            "control": {k: v.to_dict() for k, v in vt.settings.items()},
            "specimen": specimen_table(specimen), "command": command.table}
    exp = Experiment(res, result_run(res, meta, str(out or command.name)), command)
    if out is not None:
        exp.files += list(write_run(exp.run, out))
    if rerun is not None:
        from vtable.viz.rerun_scene import log_simulation

        named = {k: exp.channel(k) for k in exp.run.channels if k in FORMAT_UNITS}
        exp.files.append(log_simulation(res, rerun, named, exaggeration=exaggeration))
    return exp
