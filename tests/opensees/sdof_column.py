"""One mass on a cantilever column (kip, in): the static checks of test_opensees.py."""

MASS = 0.05         # kip s²/in
HEIGHT = 100.0      # in above the table top
K = 20.0            # kip/in: 3 E I / L³
E = 29000.0


def build(ops):
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    ops.node(1, 0.0, 0.0)
    ops.node(2, 0.0, HEIGHT)
    ops.fix(1, 1, 1, 1)
    ops.mass(2, MASS, MASS, 0.0)
    ops.geomTransf("Linear", 1)
    ops.element("elasticBeamColumn", 1, 1, 2, 10.0, E, K * HEIGHT ** 3 / (3 * E), 1)
    ops.rayleigh(8.0, 0.0, 0.0, 0.0)
    return {"base": [1], "floors": [[2]], "units": "kip-in"}
