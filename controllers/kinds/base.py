"""A horizontal controller kind: what a run's ``[table.controller] kind = "..."`` names.

A kind is one object (`ControllerKind`), one file: the keys of ``[table.controller]`` it
reads beyond the loop every kind shares, and how its terms enter the models — a control
stage (`vtable.hydraulics.stage`, kind ``"control"``) in the hydraulic element, which the
virtual table, the reduced model and the closed loop of `vtable.analytic.controlled` all
step, and the stage's parameters worked out from the declared gains.

The loop every kind shares is the report's (eqs 6.1-6.4): the displacement error e
through the P gain, velocity and ΔP feedback, the valve; `vtable.runs.lab` turns the
declared gains of that part into the servo constants (k_t = K_q k_d p, k_v, k_p). A kind's
stage adds its terms per unit of that P gain: its law returns the drive in metres of
displacement error, as the element's P law does.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

from vtable.errors import VtableError
from vtable.hydraulics.stage import Stage


class ControlUse(NamedTuple):
    """A declared controller's control stage in a table (`VirtualTable.control`): the
    stage, its parameters, and the ones a diagnosis may refit (name -> (lower, upper)
    factor of the declared value)."""

    stage: Stage
    params: dict[str, float]
    calibrated: dict[str, tuple]

    @property
    def use(self) -> tuple[Stage, dict[str, float]]:
        """(stage, parameters), as an assembly's stage list holds it."""
        return (self.stage, self.params)


@dataclass(frozen=True)
class ControllerKind:
    """One controller kind (see the module docstring).

    Parameters
    ----------
    name
        The ``kind`` a run names.
    description
        One line: what the controller does.
    keys
        The `vtable.runs.table.ControllerDescription` fields it reads beyond the shared
        loop's (displacement_gain, p, velocity_gain, pressure_gain); a declared field it
        does not read is an error naming it.
    stage
        Its control stage (None: the shared loop only).
    params
        ``params(description) -> dict`` the stage's named parameters (SI, per unit P
        gain) from the declared controller, or None when its terms are all off.
    calibrated
        Stage parameters a diagnosis may refit: name -> (lower, upper) factor of the
        declared value, optionally with the parameter's unit (``(0.5, 2.0, "s")``;
        without one it is shown as a number).
    user_keys
        Keys of its own (name -> unit), for a lab's controller file.
    """

    name: str
    description: str
    keys: tuple[str, ...] = ()
    stage: Stage | None = None
    params: Callable | None = None
    calibrated: dict[str, tuple] = field(default_factory=dict)
    user_keys: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        where = f"controller kind {self.name!r}"
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise VtableError(f"{where}: a kind's name must be an identifier")
        if self.stage is not None:
            if not isinstance(self.stage, Stage) or self.stage.kind != "control":
                raise VtableError(f"{where}: stage must be a Stage of kind 'control'")
            if self.params is None:
                raise VtableError(f"{where}: a stage needs params(description)")
        if set(self.calibrated) - set(self.stage.params if self.stage else ()):
            raise VtableError(f"{where}: calibrated names an unknown stage parameter")
        for k, v in self.calibrated.items():
            if not (isinstance(v, tuple) and len(v) in (2, 3) and 0 < v[0] <= 1 <= v[1]):
                raise VtableError(f"{where}: calibrated[{k!r}] must be (lower, upper[, unit]) "
                                  "factors with lower <= 1 <= upper")

    def stage_use(self, description) -> ControlUse | None:
        """The stage with its parameters for a declared controller, None when it adds
        none."""
        if self.stage is None:
            return None
        p = self.params(description)
        return None if p is None else ControlUse(self.stage, dict(p), dict(self.calibrated))
