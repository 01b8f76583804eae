"""Each formula written once agrees with an independent derivation: the servo law's loop
row, eq 6.16 and its inverse, the k_θ split; the frequency response against a direct solve
and python-control; no import circle through analytic/ and params/."""

import ast
import dataclasses
from pathlib import Path

import numpy as np
import pytest
import scipy.signal

from vtable.analytic import TwoDirectionalTable
from vtable.analytic.closed_forms import combined_rocking, feedback_spring, stabilizer_rocking
from vtable.analytic.pitch import two_directional
from vtable.analytic.servo import (
    ServoLoop,
    loop_row,
    open_loop_from_servo,
    servo_from_open_loop,
)
from vtable.params import OpenLoop, presets
from vtable.tables.eerc import split_rocking, virtual_table

SRC = Path(__file__).resolve().parents[2] / "src" / "vtable"


def test_loop_row_is_the_denominator_of_eq_6_15b():
    ol = OpenLoop(f_o=11.0, xi_o=0.45, k_o=30.0)
    row, b = loop_row(ol)
    w, xi, k = 2 * np.pi * 11.0, 0.45, 30.0
    # independent: x_t/x_c of the state-space model, through scipy.signal
    m = ServoLoop(ol)
    num, den = scipy.signal.ss2tf(m.A, m.B, m.C[:1], m.D[:1])
    np.testing.assert_allclose(den, [1.0, 2 * xi * w, w**2, k * w**2], rtol=1e-12)
    np.testing.assert_allclose(num[0], [0.0, 0.0, 0.0, k * w**2], rtol=1e-12, atol=1e-9)
    # the row itself: characteristic polynomial s³ - row[2] s² - row[1] s - row[0]
    np.testing.assert_allclose([1.0, -row[2], -row[1], -row[0]], den, rtol=1e-14)
    assert b == pytest.approx(k * w**2, rel=1e-15)


def test_every_model_carries_the_same_loop_row():
    p = two_directional(21.0)
    model = TwoDirectionalTable(p)
    x = {n: i for i, n in enumerate(model.states)}
    for ol, (q, v, f), inp, scale in ((p.open_loop, ("x_t", "v_t", "x_f"), 0, 1.0),
                                      (p.pitch_loop, ("x_r", "v_r", "x_m"), 1, p.height)):
        row, b = loop_row(ol)
        i = x[f]
        np.testing.assert_array_equal(model.A[i, [x[q], x[v], x[f]]], row)
        assert model.B[i, inp] == b * scale


@pytest.mark.parametrize("damping", [None, 2.0e4])
@pytest.mark.parametrize("k_v", [0.0, 1e-4])
def test_eq_6_16_inverse_of_forward_is_identity(damping, k_v):
    c = dataclasses.replace(presets.eerc_table().servo, damping=damping, k_v=k_v)
    ol = open_loop_from_servo(c)
    for solve_for, names in (("leakage", ("k_t", "beta", "k_ct")),
                             ("feedback", ("k_t", "volume", "k_p"))):
        # the unknowns start far off: only the held constants may be read
        start = dataclasses.replace(c, **{n: 3.0 * getattr(c, n) for n in names})
        back = servo_from_open_loop(ol, start, solve_for=solve_for)
        for n in names:
            assert getattr(back, n) == pytest.approx(getattr(c, n), rel=1e-10), (solve_for, n)
        # and forward(inverse(ol)) == ol
        again = open_loop_from_servo(back)
        assert (again.f_o, again.xi_o, again.k_o) == pytest.approx((ol.f_o, ol.xi_o, ol.k_o),
                                                                   rel=1e-12)


def test_eq_6_16_by_hand_without_feedback_damping():
    # independent: eq 6.16 written out for c = 0, k_v = 0 (the report's Table B.5 case)
    c = presets.eerc_table().servo
    ol = open_loop_from_servo(c)
    A, k = c.area, c.k_t
    w = np.sqrt(4 * c.beta * A**2 / (c.mass * c.volume))
    assert ol.omega_o == pytest.approx(w, rel=1e-14)
    assert ol.k_o == pytest.approx(k / A, rel=1e-14)
    assert ol.xi_o == pytest.approx(c.mass * w * (k * c.k_f + c.k_c) / (2 * A), rel=1e-14)


def test_vertical_servo_realises_the_pitch_loop():
    vt = virtual_table()
    v = vt.vertical_servo
    g = vt.table.geometry
    # the pitch DOF: I θ̈ = Σ T_i F_i with 4 actuators at lever T: m = I/(4T²)
    assert v.mass == pytest.approx(g.pitch_inertia / (4 * (g.vertical_square / 2) ** 2))
    pl = open_loop_from_servo(v)
    assert (pl.f_o, pl.xi_o, pl.k_o) == pytest.approx(
        (vt.pitch_loop.f_o, vt.pitch_loop.xi_o, vt.pitch_loop.k_o), rel=1e-12)


def test_k_theta_split_inverts_combined_rocking():
    p = two_directional(21.0)
    inertia = presets.eerc_table().geometry.pitch_inertia
    rock = presets.hybrid_rocking()
    f_c = presets.pitch_springs().f_coupled
    k_p, c_p = stabilizer_rocking(rock.k_theta, rock.c_theta, inertia, p.pitch_loop, f_c)
    r = combined_rocking(k_p, c_p, inertia, p.pitch_loop, f_c)
    assert (r["k_theta"], r["c_theta"]) == pytest.approx((rock.k_theta, rock.c_theta),
                                                         rel=1e-12)
    # the pitch loop carries the §8.6.2 springs k_v, c_v (eqs 8.28-8.29)
    sp = presets.pitch_springs()
    assert (k_p, c_p) == pytest.approx((rock.k_theta - sp.k_v, rock.c_theta - sp.c_v),
                                       rel=1e-9)
    # the two-directional model and the virtual table's stabilizers hold the same split
    assert inertia * (2 * np.pi * p.f_p) ** 2 == pytest.approx(k_p, rel=1e-12)
    vt = virtual_table()
    d_p = vt.table.geometry.stabilizer_square
    assert vt.stabilizers.stiffness * d_p**2 == pytest.approx(k_p, rel=1e-12)
    assert split_rocking(rock.k_theta, rock.c_theta, vt) == pytest.approx(
        (vt.stabilizers.stiffness, vt.stabilizers.damping), rel=1e-15)


def test_k_theta_weaker_than_the_pitch_loop_is_refused():
    p = two_directional(21.0)
    inertia = presets.eerc_table().geometry.pitch_inertia
    k_v, c_v = feedback_spring(inertia, p.pitch_loop, 2.58)
    with pytest.raises(Exception, match="pitch loop alone"):
        stabilizer_rocking(0.5 * float(k_v), float(c_v), inertia, p.pitch_loop, 2.58)


def test_freqresp_agrees_with_a_direct_solve_to_1e_9():
    model = TwoDirectionalTable(two_directional(21.0))
    f = np.geomspace(0.1, 50.0, 512)
    s = 2j * np.pi * f
    direct = model.C @ np.linalg.solve(s[:, None, None] * np.eye(8) - model.A,
                                       np.broadcast_to(model.B, (len(f), *model.B.shape)))
    ours = model.freqresp(f)
    rel = np.abs(ours - direct) / np.abs(direct)
    assert rel.max() < 1e-9
    control = pytest.importorskip("control")
    resp = control.frequency_response(model.to_control(), 2 * np.pi * f)
    theirs = np.moveaxis(np.asarray(resp.frdata if hasattr(resp, "frdata") else resp.fresp),
                         -1, 0)
    assert np.max(np.abs(ours - theirs) / np.abs(theirs)) < 1e-9


def _imports(path: Path, known: set[str]) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for a in node.names:
                full = f"{node.module}.{a.name}"
                out.add(full if full in known else node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out & known


def test_no_import_circle_through_analytic_and_params():
    files = {".".join(p.relative_to(SRC.parent).with_suffix("").parts).removesuffix(".__init__"): p
             for p in SRC.rglob("*.py")}
    graph = {m: _imports(p, set(files)) - {m} for m, p in files.items()}

    def reaches(a: str, b: str) -> bool:
        seen, todo = set(), [a]
        while todo:
            m = todo.pop()
            if m == b:
                return True
            if m not in seen:
                seen.add(m)
                todo.extend(graph.get(m, ()))
        return False

    ours = [m for m in files if m.startswith(("vtable.analytic.", "vtable.params."))]
    circles = [(m, n) for m in ours for n in graph[m] if reaches(n, m)]
    assert circles == []


def test_analytic_and_params_import_at_the_top():
    inside = []
    for p in [*SRC.joinpath("analytic").glob("*.py"), *SRC.joinpath("params").glob("*.py")]:
        for fn in ast.walk(ast.parse(p.read_text())):
            if isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                inside += [f"{p.name}:{n.lineno}" for n in ast.walk(fn)
                           if isinstance(n, ast.Import | ast.ImportFrom)
                           and not (isinstance(n, ast.Import) and n.names[0].name == "control")]
    assert inside == []


def test_one_valve_rating_for_the_appendix_c_valve_and_flow_saturation():
    from conftest import nonlinear_controllers

    from vtable import units
    from vtable.effects import get
    from vtable.effects.flow_saturation import FLOW_CAP

    vt = virtual_table()
    t = vt.table
    assert units.from_si(t.rated_velocity(), "in/s") == pytest.approx(25.0)  # Table 2.2
    assert units.from_si(t.rated_velocity("vertical"), "in/s") == pytest.approx(15.0)
    q = t.rated_flow("H1")
    assert q == pytest.approx(t.rated_velocity() * t.actuator("H1").area, rel=1e-15)
    # the appendix C valve's cap ...
    law = nonlinear_controllers(vt)[0].law
    caps = [p["max_flow"] for st, p in law.stages if st.name == FLOW_CAP.name]
    assert caps == [q]
    # ... is the flow_saturation effect's default cap v_max·A
    v_max = next(p for p in get("flow_saturation").params if p.name == "v_max")
    assert units.to_si(v_max.default, "in/s") * vt.horizontal_servo.area == pytest.approx(
        q, rel=1e-12)
    with pytest.raises(Exception, match="no servovalve"):
        t.rated_flow("P1")


def test_a_dofs_single_state_loop_is_the_projection_of_the_element():
    """`ServoLaw.dof_loop` (the reduced model's pitch loop) projects the compiled element's
    linear blocks on one DOF; against eq 6.5a written out for symmetric pressures
    P_i = T_ij p: ṗ = -(c₀k_t g k_p + c₀k_ct) p - c₀k_t g q - (c₀k_t g k_v + c₀A) q̇,
    f = A Σ T_ij², c₀ = 4β/V."""
    import numpy as np

    from vtable.hydraulics.law import group_law

    law = group_law(virtual_table(), "vertical")
    h, j = law.hydraulics, law.dofs.index("pitch")
    c0 = 4 * h.beta / h.volume
    gain = c0 * h.k_t * law.g[j]
    by_hand = (-gain * law.k_p[j] - c0 * h.k_ct, -gain, -gain * law.k_v[j] - c0 * h.area,
               h.area * np.sum(law.T[:, j] ** 2))
    np.testing.assert_allclose(law.dof_loop("pitch"), by_hand, rtol=1e-12)
