"""The rigid bodies of the virtual table and its specimen, described once (SI).

Both the MJCF builder and the analytic linear model of the virtual table read this list:
masses, centres of mass, principal inertias and the specimen's slide joints. Positions
are in the slab frame, whose origin is the centre of the horizontal actuator line
(29.7 in below the table top, §4.2.1). The specimen's damping is not on the bodies: it is
one matrix on the slides, `specimen_damping` (a building's modal damping couples its
storeys), which both models read.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vtable.analytic.structure import building_matrices, building_stiffnesses
from vtable.errors import VtableError
from vtable.params.specimen import NoSpecimen, RigidBlock, SDOFSpecimen, ShearBuilding, Specimen
from vtable.params.virtual import VirtualTable

MASS_BLOCK = np.array([2.0, 1.6, 0.6])  # m: a lumped storey mass drawn (and its inertia) as a box


@dataclass(frozen=True)
class Body:
    """A rigid body: `pos` of its frame relative to its parent's frame, centre of mass
    `com` in its own frame, principal `inertia` about the centre of mass (kg m²), and an
    optional slide joint along the slab's x with its spring `stiffness` (the storey's
    k_j). The slide's damping is not here: see `specimen_damping`."""

    name: str
    parent: str
    pos: tuple[float, float, float]
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float]
    joint: str | None = None
    stiffness: float = 0.0
    size: tuple[float, ...] = ()


def slab_body(vt: VirtualTable) -> Body:
    """Slab + ribs: 100 kips (§2.2) shared by plate and ribs in proportion to volume;
    pitch and roll inertias about the centre of mass are Table 8.1's 1251 kip-in-s², the
    twist inertia the plate's m(w² + w²)/12. `vt.com_height` (a calibrated height above the
    actuator line) replaces the shape's centre-of-mass height."""
    g, lay = vt.table.geometry, vt.layout
    w, t = g.plan_width, g.thickness
    v_plate = w * w * t
    v_ribs = 2 * lay.rib_width * w * lay.rib_depth
    z_com = (v_plate * (-t / 2) + v_ribs * (-t - lay.rib_depth / 2)) / (v_plate + v_ribs)
    h_com = z_com + g.actuator_line_depth if vt.com_height is None else vt.com_height
    return Body("slab", "world", (0.0, 0.0, -g.actuator_line_depth), g.mass, (0.0, 0.0, h_com),
                (g.pitch_inertia, g.pitch_inertia, g.mass * 2 * w * w / 12))


def _box_inertia(m: float, dims) -> tuple[float, float, float]:
    a, b, c = dims
    return (m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12)


def specimen_bodies(spec: Specimen) -> list[Body]:
    """Bodies of the specimen, children of the slab (or of each other)."""
    if isinstance(spec, NoSpecimen):
        return []
    if isinstance(spec, RigidBlock):
        ext = np.array(spec.size) if spec.size else np.ones(3)
        n = max(spec.count, 1)
        dims = (ext[0] * n, ext[2], ext[1])  # side by side along x, long side along y (§2.5)
        return [Body("specimen", "slab", (0.0, 0.0, spec.height), spec.mass, (0.0, 0.0, 0.0),
                     _box_inertia(spec.mass, dims), size=(*tuple(ext), n))]
    if isinstance(spec, SDOFSpecimen):
        return [Body("top_mass", "slab", (0.0, 0.0, spec.height), spec.mass, (0.0, 0.0, 0.0),
                     _box_inertia(spec.mass, MASS_BLOCK), joint="x_s",
                     stiffness=spec.stiffness)]
    if isinstance(spec, ShearBuilding):
        k = building_stiffnesses(spec)
        out, parent, z_prev = [], "slab", 0.0
        for j, (mj, hj, kj) in enumerate(zip(spec.masses, spec.heights, k, strict=True), 1):
            out.append(Body(f"storey{j}", parent, (0.0, 0.0, hj - z_prev), float(mj),
                            (0.0, 0.0, 0.0), _box_inertia(float(mj), MASS_BLOCK),
                            joint=f"x_s{j}", stiffness=float(kj)))
            parent, z_prev = f"storey{j}", hj
        return out
    raise VtableError(f"unsupported specimen {type(spec).__name__}")


def specimen_damping(spec: Specimen) -> np.ndarray:
    """The specimen's damping matrix C_d on its slide coordinates (N s/m), in the order of
    the slide joints of `specimen_bodies`; the one source of the specimen's damping for the
    MuJoCo table (`mjcf.builder`) and the analytic and reduced models
    (`models.linear_table.mechanics`).

    A SDOF frame: [[c_s]]. A shear building: the slides chain (storey j's joint is its
    drift d_j relative to storey j-1), so the storeys' displacements relative to the table
    are u = L d with L lower-triangular ones, and the classical damping
    C_u = M Φ diag(2 ξ_i ω_i) Φᵀ M of `analytic.structure.building_matrices` (each fixed-base
    mode i at its declared ratio ξ_i: one for all, one per mode, or Rayleigh's
    α/(2ω_i) + βω_i/2, for which C_u = α M + β K) becomes C_d = Lᵀ C_u L. A bare table or
    a rigid block: an empty (0, 0) matrix.

    Parameters
    ----------
    spec : Specimen
        The specimen.

    Returns
    -------
    numpy.ndarray
        Symmetric, positive semi-definite (n_slides, n_slides) matrix.
    """
    if isinstance(spec, SDOFSpecimen):
        return np.array([[spec.damping_coefficient]])
    if isinstance(spec, ShearBuilding):
        _, _, C_u = building_matrices(spec)
        L = np.tril(np.ones_like(C_u))
        C_d = L.T @ C_u @ L
        return (C_d + C_d.T) / 2
    if isinstance(spec, NoSpecimen | RigidBlock):
        return np.zeros((0, 0))
    raise VtableError(f"unsupported specimen {type(spec).__name__}")


def slab_frame_positions(bodies: list[Body]) -> dict[str, np.ndarray]:
    """Each body's frame origin in the slab frame at rest."""
    pos = {"slab": np.zeros(3)}
    for b in bodies:
        pos[b.name] = pos[b.parent] + np.asarray(b.pos)
    return pos
