"""Hysteretic storeys in the models: the Bouc–Wen law (`vtable.params.hysteresis`), written
once, entering the reduced model and the virtual table through the assemblies' shared
vocabulary (`Assembly.add_force` on the storey's drift coordinate), for a specimen's
declared hysteresis and for the `storey_yield` effect alike.

The storey's elastic spring k stays in both models (the slide's stiffness); the element
adds +(1 − α) k (u − u_y z) to its −k u, so the storey resists with
α k u + (1 − α) k u_y z. Its state z (dimensionless) is the reduced model's element state
(RK4 with the other states) and the virtual table's force-law controller state (the
midpoint rule at the control step, `vtable.controllers.force_law`)."""

from __future__ import annotations

from vtable.analytic.structure import storey_masses, storey_stiffnesses_of
from vtable.params.hysteresis import Hysteresis
from vtable.params.specimen import SDOFSpecimen


def bouc_wen(d: float, v: float, z, p, dz) -> float:
    """The force the hysteretic part adds to a storey of drift d and drift velocity v (on
    top of its elastic −k d): +(1 − α) k (d − u_y z), so that the storey resists with
    α k d + (1 − α) k u_y z; with ż = (v − β|v||z|^(n−1) z − γ v |z|^n)/u_y (Wen 1976,
    A = 1). p: k (N/m), alpha, u_y (m), beta, gamma, n."""
    zz = z[0]
    az = abs(zz)
    if p.n == 2.0:  # the usual exponent (a declared hysteresis's default): products
        az_n1, az_n = az, az * az
    else:  # any other exponent (storey_yield fits it): one power
        az_n1 = az ** (p.n - 1.0)
        az_n = az_n1 * az
    dz[0] = (v - p.beta * abs(v) * az_n1 * zz - p.gamma * v * az_n) / p.u_y
    return (1.0 - p.alpha) * p.k * (d - p.u_y * zz)


def storey_coordinate(spec, k: int) -> str:
    """The name of storey k's drift coordinate in both models (1-based): a SDOF frame's
    "x_s", a building's "x_s1", "x_s2", ..."""
    return "x_s" if isinstance(spec, SDOFSpecimen) else f"x_s{k}"


def add_yielding_storey(m, spec, k: int, u_y: float, alpha: float, n: float = 2.0,
                        beta: float = 0.5, gamma: float = 0.5) -> None:
    """Storey k (1-based) of `spec` yields: the Bouc–Wen element on its drift coordinate
    of assembly `m` (`ReducedAssembly` or `VirtualAssembly`), its elastic stiffness the
    specimen's (as the model carries it: a calibrated frequency moves it)."""
    stiff = storey_stiffnesses_of(spec)[k - 1]
    mass = storey_masses(spec)[k - 1]
    m.add_force(bouc_wen, storey_coordinate(spec, k), None,
                {"k": stiff, "alpha": alpha, "u_y": u_y, "beta": beta, "gamma": gamma,
                 "n": n}, states=1, mass=mass, stiffness=stiff)


def add_specimen_hysteresis(m, spec) -> None:
    """Every storey the specimen declares yielding (`spec.hysteresis`), into assembly `m`."""
    h: Hysteresis | None = getattr(spec, "hysteresis", None)
    if h is None:
        return
    stiff = storey_stiffnesses_of(spec)
    for k in h.storeys:
        u_y, alpha = h.of_storey(k, stiff[k - 1])
        add_yielding_storey(m, spec, k, u_y, alpha, h.n, h.beta, h.gamma)
