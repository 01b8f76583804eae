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
    """A horizontal displacement command (SI), its run-format [command] table, and notes
    on how it was made (what a user should know: scaling, truncation)."""

    name: str
    t: np.ndarray
    x: np.ndarray
    table: dict[str, Any]
    notes: tuple[str, ...] = ()


#: default length of the generated commands (s); an earthquake plays its whole record
DEFAULT_DURATION = 11.0


def make_command(kind: str = "random", *, duration: float | None = None,
                 band: tuple[float, float] = (0.0, 25.0), peak_in: float | None = None,
                 frequency: float = 2.0, seed: int = 0, record: str | None = None,
                 length_scale: float = 3.2801) -> Command:
    """random (band-limited, §3.2), sine, pulse or earthquake (§9.2 processing of the
    record named as `load_record` takes it: elcentro, a .AT2 or .csv file, fema:ID);
    `peak_in` is the peak displacement. `duration` (s) defaults to 11 s, and for an
    earthquake to the whole record; a shorter one takes the record's beginning (cut before
    the §9.2 integration, so the command still starts and ends at rest)."""
    if duration is not None and not (np.isfinite(duration) and duration > 0):
        raise VtableError(f"duration must be a positive number of seconds, got {duration!r}")
    if kind == "random":
        peak = units.to_si(peak_in if peak_in is not None else 0.25, "in")
        t, x = band_limited_random(duration or DEFAULT_DURATION, COMMAND_DT, band, peak=peak,
                                   seed=seed)
        return Command(f"random {band[0]:g}-{band[1]:g} Hz", t, x,
                       {"kind": "random", "band_hz": list(band), "peak_in": units.from_si(
                           peak, "in"), "seed": seed})
    if kind == "sine":
        amp = units.to_si(peak_in if peak_in is not None else 0.1, "in")
        d = duration or DEFAULT_DURATION
        t, x = sine(d, COMMAND_DT, frequency, amp, ramp=min(1.0, d / 4))
        return Command(f"sine {frequency:g} Hz", t, x,
                       {"kind": "sine", "frequency_hz": frequency,
                        "peak_in": units.from_si(amp, "in")})
    if kind == "pulse":
        amp = units.to_si(peak_in if peak_in is not None else 1.0, "in")
        t, x = pulse(duration or DEFAULT_DURATION, COMMAND_DT, width=1.0, amplitude=amp,
                     start=0.5)
        return Command("pulse", t, x, {"kind": "pulse", "peak_in": units.from_si(amp, "in")})
    if kind == "earthquake":
        return _earthquake(record, duration, peak_in, length_scale)
    raise VtableError(f"unknown command kind {kind!r}; expected random, sine, pulse or "
                      "earthquake")


def _earthquake(record: str | None, duration: float | None, peak_in: float | None,
                length_scale: float) -> Command:
    rec = load_record(record)
    peak = units.to_si(peak_in if peak_in is not None else 4.0, "in")
    time_scale = float(np.sqrt(length_scale))
    notes = list(getattr(rec, "notes", ()))
    window = None
    full = rec.duration / time_scale
    if duration is not None:
        if duration > full * (1 + 1e-9):
            raise VtableError(f"--duration {duration:g} s is longer than the processed record "
                              f"{rec.name} ({full:.2f} s after the time scale "
                              f"{time_scale:.4g})")
        window = (0.0, min(duration * time_scale, rec.duration))
        notes.append(f"first {duration:g} s of the processed record (record time 0-"
                     f"{window[1]:.2f} s)")
    cmd = process_record(rec, length_scale=length_scale, peak_displacement=peak, window=window)
    notes.append(f"§9.2 processing: length scale {length_scale:g}, time scale "
                 f"{time_scale:.4g}, integrated with zero end conditions, scaled to "
                 f"±{units.from_si(peak, 'in'):g} in peak"
                 + ("" if peak_in is not None else " (the default; --peak sets it)"))
    t_new = np.arange(0.0, cmd.time[-1] + 1e-12, COMMAND_DT)
    x = np.interp(t_new, cmd.time, cmd.displacement)
    table = {"kind": "earthquake", "record": rec.name, "length_scale": length_scale,
             "time_scale": time_scale, "peak_in": units.from_si(peak, "in")}
    return Command(f"{rec.name}", t_new, x, table, tuple(notes))


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
        if f > band:
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
        if hi > band:
            notes.append(f"the random band reaches {hi:g} Hz, beyond the table's 0-{band:g} "
                         f"Hz band ({vt.limits_source}): the table attenuates it")
    return notes


def load_table(name_or_path: str | None):
    """A table preset name (eerc, lnec-st1d) or a TOML file with a run-format [table]
    table, as the models read it (`vtable.params.lab.LabTable`)."""
    from vtable.params.lab import lab_table
    from vtable.runs.table import table_from_dict

    if name_or_path in (None, "", "eerc"):
        return lab_table(None)
    p = Path(name_or_path)
    if name_or_path.endswith(".toml") or p.is_file():
        d = read_toml(p)
        return lab_table(table_from_dict(d.get("table", d), f"{p} [table]"))
    return lab_table(table_from_dict({"preset": name_or_path}, f"--table {name_or_path}"))


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
    notes: list[str] = field(default_factory=list)

    def channel(self, name: str) -> np.ndarray:
        """A channel in its run-file unit (the report's units)."""
        return units.from_si(self.run.channels[name], self.run.units[name])


def run_experiment(specimen: Specimen, command: Command, *, vt: VirtualTable | None = None,
                   valve: str = "linear", out: str | Path | None = None,
                   rerun: str | Path | None = None, exaggeration: float = 50.0,
                   output_dt: float = 0.005, title: str = "",
                   rc_filter: bool = True,
                   effects: dict[str, dict[str, float]] | None = None) -> Experiment:
    """Simulate `command` on the table carrying `specimen`; write the run and the .rrd.
    `effects` ({name: parameters in the effect's units}) are added to the standard table
    (`vtable.effects.virtual.standard_physics`)."""
    vt = vt or virtual_table()
    if valve not in ("linear", "nonlinear"):
        raise VtableError(f"valve must be linear or nonlinear, got {valve!r}")
    if effects:
        if valve != "linear":
            raise VtableError("--valve nonlinear and --effect do not combine; the appendix C "
                              "valve is --effect valve_flow_nonlinearity --effect "
                              "flow_saturation")
        import math

        from vtable.effects.virtual import max_step, setup, standard_physics

        ph = standard_physics(specimen, effects)
        k = max(1, math.ceil(output_dt / min(max_step(ph, vt), COMMAND_DT) - 1e-9))
        built, ctl, filters = setup(ph, vt, output_dt / k)
    else:
        filters = []
        built = build(vt, specimen)
        if valve == "linear":
            ctl = standard_controllers(vt, rc_filter=("x", "twist") if rc_filter else ())
        else:
            ctl = nonlinear_controllers(vt)
    notes = [*command.notes, *check_playable(command, vt, float(built.model.opt.timestep),
                                             output_dt)]
    if effects:
        notes.append("effects on the standard table: " + ", ".join(
            f"{k}" + (f" ({', '.join(f'{p}={v:g}' for p, v in pv.items())})" if pv else "")
            for k, pv in effects.items()))
    res = Simulator(built, ctl).run(command.t, {"x": command.x}, output_dt=output_dt)
    meta = {"title": title or f"{command.name}, {specimen.title} (vtable virtual table)",
            "table": {"preset": vt.name},
            **({"control": {k: v.to_dict() for k, v in vt.settings.items()}} if vt.knobs
               else {}),
            "specimen": specimen_table(specimen), "command": command.table}
    run = result_run(res, meta, str(out or command.name))
    for fn in filters:  # the effects' output filters, on the recorded channels
        run.channels = {c: v if c in ("h_span", "acc_cmd") or c.startswith("state_")
                        else fn(v, 1.0 / output_dt) for c, v in run.channels.items()}
    exp = Experiment(res, run, command, notes=notes)
    if out is not None:
        exp.files += list(write_run(exp.run, out))
    if rerun is not None:
        from vtable.viz.rerun_scene import log_simulation

        named = {k: exp.channel(k) for k in exp.run.channels if k in FORMAT_UNITS}
        exp.files.append(log_simulation(res, rerun, named, exaggeration=exaggeration))
    return exp
