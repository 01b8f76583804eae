"""A 3-storey shear building written in OpenSees (SI), the same building tests build as
vtable's `ShearBuilding` (test_opensees.py): rigid floors (vertical and rotational DOFs
fixed: they move with the platen, as the multibody table's storey bodies do) on columns
fixed against rotation, each storey's lateral stiffness 12 E I / L³ = k; the floors'
rotational masses those of vtable's storey boxes (`tables.bodies.MASS_BLOCK`); Rayleigh
damping C = a0 M + a1 K."""

K = (4.0e6, 3.5e6, 3.0e6)        # storey stiffnesses, N/m
M = (15000.0, 15000.0, 12000.0)  # floor masses, kg
H = (1.5, 3.0, 4.5)              # floor heights above the table top, m
A0, A1 = 0.5, 0.002              # Rayleigh: 1/s, s
E = 2.0e11
BOX = (2.0, 1.6, 0.6)            # m: vtable's storey box (its inertia about y)


def build(ops):
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    ops.node(1, 0.0, 0.0)
    ops.fix(1, 1, 1, 1)
    ops.geomTransf("Linear", 1)
    below = 0.0
    for k, (kk, m, y) in enumerate(zip(K, M, H, strict=True), 2):
        ops.node(k, 0.0, y)
        ops.fix(k, 0, 1, 1)
        ops.mass(k, m, m, m * (BOX[0] ** 2 + BOX[2] ** 2) / 12)
        L = y - below
        ops.element("elasticBeamColumn", k, k - 1, k, 1.0, E, kk * L ** 3 / (12 * E), 1)
        below = y
    ops.rayleigh(A0, 0.0, 0.0, A1)
    return {"base": [1], "floors": [[2], [3], [4]]}
