"""An independent truth simulator for vtable's acceptance tests.

It shares no code with vtable (a test walks these files' imports): the report's planar
equations — one-directional (eq 7.7), two-directional (eq 8.16) and hybrid (eq 8.37)
families — with the servo-hydraulic loop written from its physical constants (eqs 6.1-6.5,
B.4-B.6, Table B.5), the effects of vtable's catalog and three outside it written out
directly, the LNEC uniaxial table, its own commands, and its own writer of the run format.

    import truth
    table = truth.eerc_table(pitch="hybrid", effects={"actuator_friction": {"friction": 3.0}})
    spec = truth.sdof(weight_kip=68.0, height_in=219.0, f_hz=2.87, xi=0.01)
    cmd = truth.random_command(duration_s=11, band_hz=(0, 25), peak_in=0.15, seed=1)
    res = truth.simulate(table, spec, cmd, fs=256.0)
    decl = truth.perturb(spec, seed=5)
    truth.write_run("out/run0", res, declared=decl, noise=0.02, seed=11)

Issue 18 adds: digital controllers (`truth.controllers`: three_variable, pid, tvc, notches,
ΔP stabilisation) on both tables, the undeclared `platen_resonator`, `force_measured`
("load_cell" | "delta_p"), per-mode and Rayleigh specimen damping, exact mis-declarations
(`misdeclare`, `platen_mass_factor`) and the linearised response x_c -> x_t (`response`).
"""

from . import controllers
from .commands import Command, earthquake_command, random_command, sine_command
from .errors import TruthError
from .linearize import jacobian, modes, response
from .runfile import campaign, write_run
from .simulate import Result, simulate
from .specimens import Specimen, building, misdeclare, none, perturb, rigid, sdof
from .tables import (
    CATALOG_NAME,
    EFFECTS,
    NEW_EFFECTS,
    OUTSIDE_CATALOG,
    Table,
    eerc_table,
    lnec_table,
)

__all__ = ["CATALOG_NAME", "EFFECTS", "NEW_EFFECTS", "OUTSIDE_CATALOG", "Command", "Result",
           "Specimen",
           "Table", "TruthError", "building", "campaign", "controllers", "earthquake_command",
           "eerc_table", "jacobian", "lnec_table", "misdeclare", "modes", "none", "perturb",
           "random_command", "response", "rigid", "sdof", "simulate", "sine_command",
           "write_run"]
