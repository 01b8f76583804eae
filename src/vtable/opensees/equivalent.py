"""An OpenSees model read as a shear building: what identification and diagnosis, whose
models hold shear buildings, see of a run made with an OpenSees specimen.

The building has the model's floors (each floor's horizontal mass and mean height) and the
fixed-base frequencies of the model's first lateral modes (OpenSees' eigen analysis: the
modes whose kinetic energy is mostly the floors' horizontal motion), so its storey
stiffnesses are those of the shear building with those masses and frequencies
(`analytic.structure.storey_stiffnesses`). A frame whose frequencies no shear building
with its masses can have keeps its first frequency, with equal storey stiffnesses. Each
mode's damping ratio is the one the model declares (ops.rayleigh: ξ = α_M/(2ω) +
(β_K + β_Kinit + β_Kcomm) ω/2; ops.modalDamping), or `DAMPING` when it declares none.

This is the only place that runs a model file, and only for `vtable simulate`
(`realised`): the building is then written into the run as data, and readers take it
from there (`vtable.params.specimen.OpenSeesSpecimen.building`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from pathlib import Path

import numpy as np

from vtable.analytic.structure import building_matrices, building_stiffnesses, fixed_base_modes
from vtable.errors import VtableError
from vtable.opensees.library import explain, opensees
from vtable.opensees.model import OpenSeesModel, build, load_model, read
from vtable.params.specimen import OpenSeesSpecimen, ShearBuilding
from vtable.units import G

DAMPING = 0.02  # of critical, every mode: assumed when the model declares no damping


def lateral_frequencies(model: OpenSeesModel) -> np.ndarray:
    """The fixed-base frequencies (Hz) of the model's first n lateral modes, n its floors."""
    return np.array(_frequencies(model.path, model.path.stat().st_mtime_ns))


@functools.cache
def _frequencies(p: Path, mtime: int) -> tuple[float, ...]:
    del mtime
    ops = opensees()
    model = read(p, ops, build(p, ops))
    n = len(model.floors)
    n_dof = int(np.count_nonzero(~model.fixed & (model.masses > 0)))
    out: list[float] = []
    for want in sorted({n, min(2 * n, n_dof), min(3 * n, n_dof)}):
        if want < n:
            continue
        try:  # ARPACK needs fewer modes than DOFs; LAPACK's dense solver takes any
            lam = ops.eigen(want) if want < n_dof - 1 else ops.eigen("-fullGenLapack", want)
        except Exception as e:  # openseespy raises its own error type
            raise VtableError(f"{p}: OpenSees' eigen analysis failed ({explain(e)})") from None
        out = _lateral(ops, model, lam, n)
        if len(out) == n:
            break
    return out


def _lateral(ops, model: OpenSeesModel, lam, n: int) -> list[float]:
    """The frequencies (Hz) of the modes among `lam` whose kinetic energy is mostly the
    floors' horizontal motion, the first n."""
    out = []
    for k, lk in enumerate(lam, 1):
        phi = np.array([(ops.nodeEigenvector(t, k) + [0.0] * 3)[:3] for t in model.nodes])
        ke = model.masses * phi ** 2
        floors = [model.index(t) for f in model.floors for t in f]
        if ke[floors, 0].sum() > 0.5 * ke.sum() and lk > 0:
            out.append(math.sqrt(lk) / (2 * math.pi))
        if len(out) == n:
            break
    return out


def modal_damping(model: OpenSeesModel, freqs: np.ndarray) -> tuple[np.ndarray, str]:
    """Each lateral mode's damping ratio as the model declares it, and how it was had."""
    w = 2 * math.pi * np.asarray(freqs, dtype=float)
    if model.damping is None:
        return np.full(len(w), DAMPING), f"{DAMPING:.0%} of critical assumed (the model " \
            "declares no ops.rayleigh or ops.modalDamping)"
    how, v = model.damping
    if how == "rayleigh":
        a_m, b_k = v[0], sum(v[1:4])
        return a_m / (2 * w) + b_k * w / 2, "its Rayleigh damping (ops.rayleigh)"
    xi = np.array(v[:len(w)] if len(v) > 1 else v * len(w), dtype=float)
    if len(xi) < len(w):
        xi = np.concatenate([xi, np.full(len(w) - len(xi), xi[-1])])
    return xi, "its modal damping (ops.modalDamping)"


def equivalent_building(spec: OpenSeesSpecimen, depth: float) -> tuple[ShearBuilding, str]:
    """The shear building standing for `spec` on a table whose actuator line is `depth`
    (m) below its top, and a note saying what was read and assumed. Runs the model file
    (`load_model`)."""
    model = load_model(spec.model)
    freqs = lateral_frequencies(model)
    weights = tuple(float(w) for w in model.floor_masses * G)
    heights = tuple(float(h) for h in model.floor_heights + depth)
    xi, damped = modal_damping(model, freqs)
    xi = np.clip(xi, 0.0, 1.0)
    damping = float(xi[0]) if np.allclose(xi, xi[0], rtol=1e-9) else tuple(map(float, xi))
    kw = {"weights": weights, "heights": heights, "damping": damping,
          "title": f"{spec.title} (as a shear building)", "source": str(model.path)}
    try:
        b = ShearBuilding(frequencies=tuple(map(float, freqs)), **kw)
        building_stiffnesses(b)
        how = "its first " + ", ".join(f"{f:.3g}" for f in freqs) + " Hz lateral modes"
    except VtableError:
        unit = ShearBuilding(stiffnesses=(1.0,) * len(weights), **kw)
        M, K, _ = building_matrices(unit)
        w, _ = fixed_base_modes(M, K)
        k = (2 * math.pi * freqs[0] / w[0]) ** 2
        b = ShearBuilding(stiffnesses=(k,) * len(weights), **kw)
        how = (f"its first lateral mode ({freqs[0]:.3g} Hz) with equal storeys (no shear "
               f"building with its masses has its modes {', '.join(f'{f:.3g}' for f in freqs)}"
               " Hz)")
    note = (f"the OpenSees model {model.path.name} is read as a {len(weights)}-storey shear "
            f"building: its floors' masses and heights, {how}, {damped}")
    return b, note


def realised(spec: OpenSeesSpecimen, depth: float) -> tuple[OpenSeesSpecimen, str]:
    """`spec` with its model as data (`OpenSeesSpecimen.building`: `equivalent_building`
    on a table whose actuator line is `depth` m below its top), for `vtable simulate` to
    write into its run; and the note saying what was read."""
    b, note = equivalent_building(spec, depth)
    return dataclasses.replace(spec, building=b), note
