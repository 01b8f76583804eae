"""A hand-derived linear model of the multibody virtual table (no MuJoCo).

It carries everything the multibody table has that the report's eq 8.16 lacks, so that
the MuJoCo model can be checked against it: the slab's centre of mass 20 in above the
actuator line (inertial x-θ coupling m e), pitch inertia about the pivot I + m e², the
specimen's rotational inertia, all five slab DOFs, every actuator along its own line (its
Jacobian from the geometry), the DOF controllers and the cross-connected stabilizers
(their own linear matrices, not a copy), and the geometric stiffness of gravity and of the
pit-pressure force under rotation (small-angle Hessian of the potential,
z ≈ c - aθ + bφ + aφψ + bθψ - c(θ² + φ²)/2 for a point (a, b, c) of the slab frame).
With e = 0, no geometric stiffness and lumped loops it is the report's eq 8.16 (tested).

Coordinates q = [x, z, roll φ, pitch θ, twist ψ, x_s...]; inputs the five DOF commands.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from vtable.analytic.base import LinearModel
from vtable.controllers import DOFS, LinearController, standard_controllers
from vtable.params.specimen import NoSpecimen, Specimen
from vtable.params.virtual import VirtualTable
from vtable.tables.bodies import (
    slab_body,
    slab_frame_positions,
    specimen_bodies,
    specimen_damping,
)
from vtable.units import G

SLAB_DOFS = ("x", "z", "roll", "pitch", "twist")


def _rot_jacobian(r: np.ndarray) -> np.ndarray:
    """∂p/∂[x, z, φ, θ, ψ] of a slab-frame point r (3 x 5), small angles."""
    x, y, z = (float(v) for v in r)
    # columns: e_x, e_z, e_x × r, e_y × r, e_z × r (written out: this runs in every fit)
    return np.array([[1.0, 0.0, 0.0, z, -y],
                     [0.0, 0.0, -z, 0.0, x],
                     [0.0, 1.0, y, -x, 0.0]])


def _height_hessian(a: float, b: float, c: float) -> np.ndarray:
    """∂²z/∂(φ, θ, ψ)² of a slab-frame point (a, b, c) at rest."""
    return np.array([[-c, 0.0, a], [0.0, -c, b], [a, b, 0.0]])


def mechanics(vt: VirtualTable, specimen: Specimen, *, gravity: bool = True,
              com_offset: bool = True, body_inertia: bool = True, jacobian: bool = True):
    """Small-motion mass, stiffness and damping matrices of the slab (x, z, φ, θ, ψ) and
    the specimen's slides, and the actuators' extension Jacobian; also used by the reduced
    model of the diagnosis (without the Jacobian, `jacobian=False`: it lumps the actuators,
    and the Jacobian was most of the time of a build there). The slide block of C is the
    specimen's full damping matrix (`tables.bodies.specimen_damping`: a building's modal
    damping couples its storeys). Returns (M, K, C, Ja or None, coordinate names, slide
    bodies, slab-frame positions)."""
    bodies = specimen_bodies(specimen)
    sb = slab_body(vt)
    pos = slab_frame_positions(bodies)
    slides = [b for b in bodies if b.joint]
    nq = 5 + len(slides)
    M = np.zeros((nq, nq))
    K = np.zeros((nq, nq))
    Cd = np.zeros((nq, nq))
    rot = slice(2, 5)

    def add_body(mass, r, inertia, chain):
        J = np.zeros((3, nq))
        J[:, :5] = _rot_jacobian(r)
        for i in chain:
            J[0, 5 + i] = 1.0
        M[:, :] += mass * J.T @ J
        M[rot, rot] += np.diag(inertia)
        if gravity:
            H = _height_hessian(*r)
            K[rot, rot] += mass * G * H
            for i in chain:  # z ≈ ... - x_s θ: ∂²z/∂x_s∂θ = -1
                K[5 + i, 3] += -mass * G
                K[3, 5 + i] += -mass * G

    com = np.array(sb.com) if com_offset else np.zeros(3)
    add_body(sb.mass, com, sb.inertia, [])
    chain: list[int] = []
    for b in bodies:
        r = pos[b.name] + np.asarray(b.com)
        if b.joint:
            i = slides.index(b)
            chain = [*chain, i]
            K[5 + i, 5 + i] += b.stiffness
        add_body(b.mass, r, b.inertia if body_inertia else (0.0, 0.0, 0.0),
                 chain if b.joint else [])
    Cd[5:, 5:] += specimen_damping(specimen)
    if gravity:  # the pit-pressure force, world vertical at the bottom-face centre
        z_p = vt.pivot_depth - vt.table.geometry.thickness
        weight = (sb.mass + sum(b.mass for b in bodies)) * G
        K[rot, rot] -= weight * _height_hessian(0.0, 0.0, z_p)
    names = [*SLAB_DOFS, *(b.joint for b in slides)]
    if not jacobian:
        return M, K, Cd, None, names, slides, pos
    acts = vt.actuators
    Ja = np.zeros((len(acts), nq))
    pivot = np.array([0.0, 0.0, -vt.pivot_depth])
    for i, a in enumerate(acts):
        r = np.asarray(a.slab_point) - pivot
        Ja[i, :5] = a.axis @ _rot_jacobian(r)
    return M, K, Cd, Ja, names, slides, pos


class VirtualTableModel(LinearModel):
    """Linearized virtual table about rest, built from the same parameter objects and
    controller matrices as the multibody simulation.

    `gravity=False` drops the geometric stiffness; `com_offset=False` puts the slab's
    centre of mass on the actuator line; `body_inertia=False` drops the specimen bodies'
    own rotational inertia (the report's models treat them as point masses).
    """

    def __init__(self, vt: VirtualTable, specimen: Specimen | None = None,
                 controllers: Sequence[LinearController] | None = None, *,
                 gravity: bool = True, com_offset: bool = True, body_inertia: bool = True,
                 title: str = "") -> None:
        specimen = specimen or NoSpecimen()
        self.vt, self.specimen = vt, specimen
        ctrls = list(controllers) if controllers is not None else standard_controllers(vt)
        acts = vt.actuators
        names = tuple(a.name for a in acts)
        n = len(names)
        for c in ctrls:
            c.bind(names)
        M, K, Cd, Ja, _, slides, pos = mechanics(vt, specimen, gravity=gravity,
                                                  com_offset=com_offset,
                                                  body_inertia=body_inertia)
        nq = M.shape[0]
        # controllers: ż = A z + Bs [Ja q; Ja q̇] + Bc c ; F = C z + Ds [...] + Dc c
        zs = [len(c.state_names) for c in ctrls]
        nz = sum(zs)
        Ac = np.zeros((nz, nz))
        Bsq, Bsv = np.zeros((nz, nq)), np.zeros((nz, nq))
        Bcc = np.zeros((nz, len(DOFS)))
        Fz, Fq, Fv, Fc = (np.zeros((n, nz)), np.zeros((n, nq)), np.zeros((n, nq)),
                          np.zeros((n, len(DOFS))))
        off = 0
        for c, k in zip(ctrls, zs, strict=True):
            idx = [names.index(a) for a in c.actuators]
            sl = slice(off, off + k)
            Ac[sl, sl] = c.A
            Bsq[sl] = c.Bs[:, :n] @ Ja
            Bsv[sl] = c.Bs[:, n:] @ Ja
            Bcc[sl] = c.Bc
            Fz[idx, sl] = c.C
            Fq[idx] += c.Ds[:, :n] @ Ja
            Fv[idx] += c.Ds[:, n:] @ Ja
            Fc[idx] += c.Dc
            off += k
        Minv = np.linalg.inv(M)
        ns = 2 * nq + nz
        A = np.zeros((ns, ns))
        A[:nq, nq:2 * nq] = np.eye(nq)
        A[nq:2 * nq, :nq] = Minv @ (-K + Ja.T @ Fq)
        A[nq:2 * nq, nq:2 * nq] = Minv @ (-Cd + Ja.T @ Fv)
        A[nq:2 * nq, 2 * nq:] = Minv @ Ja.T @ Fz
        A[2 * nq:, :nq] = Bsq
        A[2 * nq:, nq:2 * nq] = Bsv
        A[2 * nq:, 2 * nq:] = Ac
        B = np.zeros((ns, len(DOFS)))
        B[nq:2 * nq] = Minv @ Ja.T @ Fc
        B[2 * nq:] = Bcc
        e = np.eye(ns)
        outputs: dict[str, tuple] = {}
        for j, d in enumerate(SLAB_DOFS):
            name = {"x": "x_t", "z": "z_t", "pitch": "theta"}.get(d, d)
            outputs[name] = (e[j], None)
            outputs[f"a_{name}"] = (A[nq + j], B[nq + j])
        self.heights = [float(pos[b.name][2]) for b in slides]
        if slides:
            h = self.heights[-1]
            outputs["theta_h"] = (h * e[3], None)
            outputs["x_eff"] = (e[0] + h * e[3], None)
            for i, b in enumerate(slides):
                outputs[b.joint] = (e[5 + i], None)
            top = sum(e[5 + i] for i in range(len(slides)))
            outputs["x_st"] = (e[0] + h * e[3] + top, None)
        for i, a in enumerate(names):
            outputs[f"ext_{a}"] = (np.concatenate([Ja[i], np.zeros(nq + nz)]), None)
            outputs[f"force_{a}"] = (np.concatenate([Fq[i], Fv[i], Fz[i]]), Fc[i])
        self.Ja, self.n_q = Ja, nq
        states = ([*SLAB_DOFS, *(b.joint for b in slides)]
                  + [f"d{s}" for s in (*SLAB_DOFS, *(b.joint for b in slides))]
                  + [s for c in ctrls for s in c.state_names])
        inputs = tuple(f"{d}_c" for d in DOFS)
        super().__init__(**self._build(A, B, states, inputs, outputs,
                                       title=title or f"virtual table linear model "
                                                      f"({specimen.title})"))
