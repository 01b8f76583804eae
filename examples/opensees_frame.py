"""A 3-storey, one-bay steel moment frame for the table, as a lab would model it in
OpenSees (kip, in, s): fibre columns (W6x15, Steel02, 50 ksi) that yield, stiff beams,
15 kip per floor, 2 % Rayleigh damping. vtable calls build(ops) (docs/opensees.md).

Section dimensions: AISC Steel Construction Manual, W6x15 (d 5.99 in, b_f 5.99 in,
t_f 0.260 in, t_w 0.230 in). Steel02 parameters: Filippou et al. (1983), R0 = 18,
cR1 = 0.925, cR2 = 0.15, 1 % strain hardening.
"""

import math

BAY = 72.0                  # in
STOREY = 90.0               # in, each of the three
FLOOR_WEIGHT = 15.0         # kip per floor, half at each joint
G = 386.089                 # in/s²
E, FY, B = 29000.0, 50.0, 0.01
D, BF, TF, TW = 5.99, 5.99, 0.260, 0.230


def column_section(ops, tag: int) -> None:
    """W6x15 bending about its strong axis: flanges and web as fibres of Steel02."""
    ops.uniaxialMaterial("Steel02", tag, FY, E, B, 18.0, 0.925, 0.15)
    ops.section("Fiber", tag)
    y = D / 2
    ops.patch("rect", tag, 4, 1, y - TF, -BF / 2, y, BF / 2)
    ops.patch("rect", tag, 4, 1, -y, -BF / 2, -y + TF, BF / 2)
    ops.patch("rect", tag, 8, 1, -y + TF, -TW / 2, y - TF, TW / 2)


def build(ops):
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    column_section(ops, 1)
    ops.beamIntegration("Lobatto", 1, 1, 4)
    ops.geomTransf("PDelta", 1)   # columns
    ops.geomTransf("Linear", 2)   # beams
    m = FLOOR_WEIGHT / G / 2
    floors = []
    for level in range(4):
        y = level * STOREY
        for j, x in enumerate((-BAY / 2, BAY / 2)):
            ops.node(10 * level + j + 1, x, y)
        if level == 0:
            ops.fix(1, 1, 1, 1)
            ops.fix(2, 1, 1, 1)
            continue
        left, right = 10 * level + 1, 10 * level + 2
        for n in (left, right):
            ops.mass(n, m, m, 0.0)
        floors.append([left, right])
        for j in (1, 2):  # the columns below this floor
            ops.element("forceBeamColumn", 100 * level + j, 10 * (level - 1) + j,
                        10 * level + j, 1, 1)
        # a stiff beam (10 x the column's stiffness)
        ops.element("elasticBeamColumn", 1000 + level, left, right, 4.43, E, 291.0, 2)
    # 2 % at the first two modes' neighbourhood (1.8 and 6 Hz): C = a0 M + a1 K
    w1, w2, xi = 2 * math.pi * 1.8, 2 * math.pi * 6.0, 0.02
    a0, a1 = 2 * xi * w1 * w2 / (w1 + w2), 2 * xi / (w1 + w2)
    ops.rayleigh(a0, 0.0, a1, 0.0)
    return {"base": [1, 2], "floors": floors, "units": "kip-in"}
