"""Issue 31, the instant diagnosis: the pieces that make it cost seconds, each against what
it replaces or an independent reference, and the diagnosis they make on the independent
truth simulator's campaigns (tests/truth: declared specimen perturbed, 1 % noise).

- a linear model's outputs stepped in its modal coordinates equal the integrator's;
- the secant Jacobian is the forward-difference one where it is taken, exact for a linear
  map after Broyden's updates, and a fit with it reaches the forward-difference fit's
  minimum; the fit handed n + 1 rows instead of all takes the same steps;
- the amplitude screen reads no amplitude dependence where the missing effect is linear and
  plenty where it is friction, and keeps the nonlinear candidates out only in the first;
- the diagnosis ends where a plain fit of the right model ends (the same final error), and
  on a Dask scheduler of separate processes as on the local cluster.
"""

from __future__ import annotations

import functools
import socket
import subprocess
import sys
import time

import numpy as np
import pytest
import scipy.optimize
import truth

from vtable.diagnose.campaign import Campaign
from vtable.diagnose.engine import Diagnoser
from vtable.diagnose.model import TableModel
from vtable.diagnose.screen import Z_SCREEN, linear_explains, nonlinearity_evidence
from vtable.diagnose.secant import Families, Secant, compact
from vtable.effects.registry import BUILT_IN
from vtable.errors import VtableError
from vtable.models.physics import Physics, nominal_open_loop
from vtable.models.reduced import ReducedModel
from vtable.runs import read_run


@functools.cache
def truth_campaign(effects: tuple[tuple[str, float], ...], pitch: str = "none") -> list:
    """Two 12 s random runs (0.1 and 0.4 in) and El Centro at 3 in on the truth's EERC
    table with `effects` ((name, value) of its first parameter), the SDOF frame declared
    3 % off in frequency, 1 % noise."""
    import tempfile
    from pathlib import Path

    folder = Path(tempfile.mkdtemp(prefix="instant-"))
    spec = truth.sdof(68.0, 219.0, 2.87, 0.02)
    decl = truth.perturb(spec, seed=7, frequency=0.03, damping=1.5, weight=0.05)
    table = truth.eerc_table(pitch=pitch, effects={n: ({"friction": v} if n ==
                                                        "actuator_friction" else {})
                                                   for n, v in effects})
    cmds = [("random_0", truth.random_command(12.0, (0, 25), peak_in=0.1, seed=1)),
            ("random_1", truth.random_command(12.0, (0, 25), peak_in=0.4, seed=2)),
            ("earthquake", truth.earthquake_command("elcentro", peak_in=3.0))]
    paths = []
    for k, (name, cmd) in enumerate(cmds):
        res = truth.simulate(table, spec, cmd, fs=200.0)
        paths.append(truth.write_run(folder / name, res, decl, noise=0.01, seed=40 + k)[0])
    return [read_run(p) for p in paths]


PITCH = ((), "hybrid")  # the table's pitch (linear) the starting model lacks
FRICTION = ((("actuator_friction", 3.0),), "none")  # 3 kip of friction


@pytest.mark.parametrize("effects", sorted(e for e in BUILT_IN if e != "storey_yield"))
def test_modal_outputs_equal_the_integrator(effects):
    """Every model the catalog makes: the channels the targets need, at every other
    sample, equal `simulate`'s to 1e-9 of their peak (a linear one: the same first-order
    hold, mode by mode; a nonlinear one: its channels from the integrator's histories at
    those samples, or, behind an output filter, filtered whole)."""
    runs = truth_campaign(*PITCH)
    c = Campaign.of(runs)
    m = ReducedModel(Physics(nominal_open_loop(c.table), c.specimen, {effects: {}}), c.table)
    r = c.runs[2]
    t, x = r.time[:1500], r.channel("h_span")[:1500]
    full = m.simulate(t, x)
    names = ["avg_hdisp", "avg_hacc", "h1_force", "h2_force", "acc_n_ne", "pot_n_sw"]
    fast = m.outputs(t, x, names, step=2)
    assert set(fast) == set(names)
    for k in names:
        assert np.max(np.abs(fast[k] - full[k][::2])) <= 1e-9 * np.max(np.abs(full[k])), k
    assert fast["h1_force"] is fast["h2_force"]  # one lumped actuator, computed once
    if m.linear:
        assert m._modal() is not None  # the stable, well-conditioned modal path was taken


def test_a_filtered_nonlinear_model_steps_its_dynamics_once(monkeypatch):
    """A nonlinear model behind an output filter (friction and the anti-aliasing filter):
    `outputs` gives `simulate`'s channels to the bit, filtering only those asked; a model
    with the same dynamics and another cut-off reads the histories kept
    (`kept_histories`: no integration), one with other friction integrates again; the
    kept arrays are read-only, and a filter that changes its input in place is handed a
    copy."""
    from vtable.models.modal import filtered
    from vtable.models.reduced_parts import kept_histories

    runs = truth_campaign(*PITCH)
    c = Campaign.of(runs)
    r = c.runs[2]
    t, x = r.time[:1500], r.channel("h_span")[:1500]
    names = ["avg_hdisp", "avg_hacc", "h1_force", "h2_force", "acc_n_ne", "pot_n_sw"]
    calls = [0]
    integrate = ReducedModel.histories

    def counted(self, *a):
        calls[0] += 1
        return integrate(self, *a)

    monkeypatch.setattr(ReducedModel, "histories", counted)

    def model(friction, cutoff):
        return ReducedModel(Physics(nominal_open_loop(c.table), c.specimen, {
            "actuator_friction": {"friction": friction}, "sensor_filter": {"cutoff_hz": cutoff}}),
            c.table)

    for friction, cutoff, integrated in ((2.0, 60.0, 1), (2.0, 35.0, 0), (2.5, 35.0, 1)):
        m = model(friction, cutoff)
        assert not m.linear and m.assembly.filters
        calls[0] = 0
        fast = m.outputs(t, x, names, step=2)
        assert calls[0] == integrated, (friction, cutoff)
        full = m.simulate(t, x)
        for k in names:
            np.testing.assert_array_equal(fast[k], full[k][::2])
        assert fast["h1_force"] is fast["h2_force"]
    assert not kept_histories(model(2.0, 35.0), t, x).q.flags.writeable

    ro = np.arange(6.0)
    ro.flags.writeable = False

    def in_place(v, fs):
        v *= 2.0
        return v

    out = filtered([(in_place, None)], {"a": ro, "b": ro}, 200.0)
    np.testing.assert_array_equal(out["a"], 2 * np.arange(6.0))
    assert out["a"] is out["b"]  # one signal, filtered once
    np.testing.assert_array_equal(ro, np.arange(6.0))


def test_secant_jacobian():
    rng = np.random.default_rng(3)
    A = rng.normal(size=(40, 5))
    b = rng.normal(size=40)
    lo, hi = np.full(5, -10.0), np.full(5, 10.0)
    x = rng.normal(size=5)
    np.testing.assert_allclose(Secant(lambda x: A @ x + b, lo, hi).at(x), A, atol=1e-6)
    s = Secant(lambda x: A @ x + b, lo, hi)
    np.testing.assert_allclose(s.jac(x), A, atol=1e-6)  # the first: forward differences
    assert s.evals == 1 + 5
    for _ in range(3):  # Broyden's updates keep a linear map's Jacobian exact
        x = x + rng.normal(size=5) * 0.1
        s.fun(x)
        np.testing.assert_allclose(s.jac(x), A, atol=1e-6)
    assert s.evals == 1 + 5 + 3  # one evaluation per step, no differences

    # Rosenbrock's residuals: the secant fit ends at the forward-difference fit's minimum
    def rosen(x):
        return np.array([10 * (x[1] - x[0] ** 2), 1 - x[0]])

    s = Secant(rosen, np.full(2, -5.0), np.full(2, 5.0))
    sol = scipy.optimize.least_squares(s.fun, [-1.2, 1.0], jac=s.jac, xtol=1e-12,
                                       ftol=1e-12, gtol=1e-12, bounds=(-5, 5))
    ref = scipy.optimize.least_squares(rosen, [-1.2, 1.0], xtol=1e-12, ftol=1e-12,
                                       gtol=1e-12, bounds=(-5, 5))
    np.testing.assert_allclose(sol.x, ref.x, atol=1e-6)
    np.testing.assert_allclose(sol.x, [1.0, 1.0], atol=1e-6)

    # a fit taking every Jacobian by differences: the covariance's Jacobian where it ends
    # is the last one it took (no second set of simulations), and equals a fresh one
    s = Secant(rosen, np.full(2, -5.0), np.full(2, 5.0), refresh=1)
    sol = scipy.optimize.least_squares(s.fun, [-1.2, 1.0], jac=s.jac, bounds=(-5, 5),
                                       max_nfev=7)
    n = s.evals
    np.testing.assert_array_equal(s.at_end(sol.x), Secant(rosen, s.lo, s.hi).at(sol.x))
    assert s.evals == n
    s.at_end(sol.x + 0.1)  # elsewhere: taken there
    assert s.evals == n + 3


def test_the_compacted_fit_takes_the_same_steps():
    """`compact`: n + 1 rows keeping JᵀJ and Jᵀf (with the residual (‖f‖, 0, …)), from the
    Gram matrix's Cholesky factor, and from a QR where that would lose digits (columns
    nearly dependent) or does not exist (a zero column, f = 0). `Secant.solve`: on a
    damped sine's 400 residuals, the same steps as `least_squares` on every row (the same
    evaluations, the same end), with the whole residual and Jacobian returned."""
    rng = np.random.default_rng(7)
    J, f = rng.normal(size=(400, 6)) * np.logspace(-3, 3, 6), rng.normal(size=400)
    near = J.copy()
    near[:, 5] = near[:, 4] * 2 + 1e-9 * rng.normal(size=400)  # independent part 1e-12
    zero = J.copy()
    zero[:, 2] = 0.0
    close = J.copy()  # independent part 1e-7: the Gram matrix's factor exists, inexact
    close[:, 5] = close[:, 4] * 2 + 1e-7 * np.linalg.norm(J[:, 4]) * rng.normal(size=400) / 20
    s_close = np.linalg.svd(compact(f, close), compute_uv=False)
    np.testing.assert_allclose(s_close[-1], np.linalg.svd(close, compute_uv=False)[-1],
                               rtol=1e-6)  # (from the QR: 5e-2 off from the Gram's factor)
    for A, r in ((J, f), (near, f), (zero, f), (close, f), (J, np.zeros(400))):
        C = compact(r, A)
        assert C.shape == (7, 6)
        e = np.zeros(7)
        e[0] = np.sqrt(r @ r)
        scale = np.outer(np.linalg.norm(A, axis=0), np.linalg.norm(A, axis=0)) + 1e-300
        np.testing.assert_allclose((C.T @ C) / scale, (A.T @ A) / scale, atol=1e-12)
        np.testing.assert_allclose(C.T @ e, A.T @ r, rtol=1e-10,
                                   atol=1e-12 * np.linalg.norm(A) * np.linalg.norm(r))

    t = np.linspace(0.0, 4.0, 400)
    y = 1.3 * np.exp(-0.7 * t) * np.sin(5.0 * t + 0.4) + 0.01 * rng.normal(size=400)

    def sine(x):
        return x[0] * np.exp(-x[1] * t) * np.sin(x[2] * t + x[3]) - y

    lo, hi = np.array([0.1, 0.0, 3.0, -1.0]), np.array([5.0, 3.0, 7.0, 2.0])
    for refresh in (1, 4):
        full, small = Secant(sine, lo, hi, refresh=refresh), Secant(sine, lo, hi,
                                                                     refresh=refresh)
        kw = dict(bounds=(lo, hi), xtol=1e-10, ftol=1e-10, max_nfev=40)
        ref = scipy.optimize.least_squares(full.fun, [1.0, 0.5, 4.6, 0.0], jac=full.jac,
                                           **kw)
        sol = small.solve(np.array([1.0, 0.5, 4.6, 0.0]), **kw)
        assert small.evals == full.evals and sol.nfev == ref.nfev and sol.njev == ref.njev
        np.testing.assert_allclose(sol.x, ref.x, rtol=1e-9)
        np.testing.assert_allclose(sol.x[:3], [1.3, 0.7, 5.0], rtol=0.05)
        np.testing.assert_array_equal(sol.fun, sine(sol.x))  # the whole residual ...
        assert sol.jac.shape == (400, 4)  # ... and Jacobian where it ended
        np.testing.assert_allclose(sol.jac, ref.jac, rtol=1e-6, atol=1e-9)

    # ten parameters: a Jacobian's differences push the point out of those `Secant` keeps,
    # and its residual there is not evaluated again
    B = rng.normal(size=(400, 10))
    z = B @ np.linspace(0.5, 1.5, 10)

    def wavy(x):
        return B @ x + 0.3 * np.sin(B @ x) - z - 0.3 * np.sin(z)

    lo10, hi10 = np.full(10, -3.0), np.full(10, 3.0)
    full, small = Secant(wavy, lo10, hi10, refresh=1), Secant(wavy, lo10, hi10, refresh=1)
    kw = dict(bounds=(lo10, hi10), xtol=1e-12, ftol=1e-12, max_nfev=20)
    ref = scipy.optimize.least_squares(full.fun, np.zeros(10), jac=full.jac, **kw)
    sol = small.solve(np.zeros(10), **kw)
    assert small.evals == full.evals and sol.nfev == ref.nfev
    np.testing.assert_allclose(sol.x, ref.x, rtol=1e-8, atol=1e-10)
    assert sol.cost == pytest.approx(ref.cost, rel=1e-12)


def test_rivals_share_their_family_jacobian():
    """`Families`: a family's first start takes its own forward-difference Jacobian, the
    same `least_squares`' first `jac` takes (the same steps, to the bit); a later start
    of the family takes the others' columns from there and differences only its own
    parameters' (one evaluation each, beside its residual); another family its own in
    full. On a nonlinear map the shared columns are the first start's, not the new
    point's; the own columns are the new point's."""
    def f(x):  # nonlinear in every parameter: columns differ from point to point
        return np.array([x[0] ** 2 + x[1], np.sin(x[1]) * x[2], x[0] * x[2] ** 2, x[2] - x[0]])

    lo, hi = np.full(3, -5.0), np.full(3, 5.0)
    own = np.array([2])
    fam = Families(own)
    x1, x2, x3 = np.array([0.3, 0.7, 1.1]), np.array([0.5, 0.2, 1.6]), np.array([1, 1, 1.0])

    def fit(x, seeded):
        s = Secant(f, lo, hi)
        if seeded:
            fam.seed(s, x, "fitted" if x is not x3 else "declared")
        sol = scipy.optimize.least_squares(s.fun, x, jac=s.jac, bounds=(lo, hi), max_nfev=3)
        return s, sol

    s, sol = fit(x1, True)
    ref_s, ref = fit(x1, False)
    np.testing.assert_array_equal(sol.x, ref.x)  # the family's first: as unseeded
    # (its residual at the start asked twice: a fit's `_cost` keeps it, no simulation)
    assert s.evals == ref_s.evals + 1
    s = Secant(f, lo, hi)
    fam.seed(s, x2, "fitted")
    assert s.evals == 1 + len(own)  # its residual, and its own column
    J, J1, J2 = s._J, Secant(f, lo, hi).at(x1), Secant(f, lo, hi).at(x2)
    np.testing.assert_array_equal(J[:, :2], J1[:, :2])  # the family's columns
    np.testing.assert_array_equal(J[:, 2], J2[:, 2])  # its own, where it is
    assert np.abs(J1[:, :2] - J2[:, :2]).max() > 0.1  # (they differ on this map)
    s = Secant(f, lo, hi)
    fam.seed(s, x3, "declared")  # another family: its own Jacobian, in full
    assert s.evals == 1 + 3
    np.testing.assert_array_equal(s._J, Secant(f, lo, hi).at(x3))


def test_a_point_asked_again_is_not_simulated_again(monkeypatch):
    """`TableModel._cost` keeps its last `COSTS_KEPT` residual vectors: the same point on
    the same start, layout and campaign costs no simulation and gives the same vector (a
    copy: changing it changes nothing kept); another point, start or layout does."""
    from vtable.diagnose.residuals import COSTS_KEPT

    runs = truth_campaign(*PITCH)
    c = Campaign.of(runs)
    m = TableModel()
    m.vt, m.declared, m.campaign_ = c.table, c.specimen, c
    start = Physics(nominal_open_loop(c.table), c.specimen, {"pitch_flexibility": {}})
    c = c.training_for(start)
    lay = m._layout(start)
    x = m._pack(start, lay)
    sims = []
    real = TableModel._residuals
    monkeypatch.setattr(TableModel, "_residuals",
                        lambda self, ph, camp: sims.append(1) or real(self, ph, camp))
    f = m._cost(x, start, lay, c)
    assert len(sims) == 1 and len(f) > c.n_target > 1000
    f[:] = 0.0  # the caller's copy
    again = m._cost(x.copy(), start, lay, c)
    assert len(sims) == 1 and np.any(again != 0.0)
    np.testing.assert_array_equal(again, real(m, m._unpack(x, start, lay), c).tolist() +
                                  list(m._priors(x, lay, c)))
    y = x.copy()
    y[0] += 1e-3
    m._cost(y, start, lay, c)
    assert len(sims) == 2  # another point
    m._cost(x, start.with_effect("force_feedback_filter"), lay, c)
    assert len(sims) == 3  # another start (the same layout object: not the same model)
    for k in range(COSTS_KEPT):  # the oldest forgotten
        z = x.copy()
        z[1] += 1e-4 * (k + 1)
        m._cost(z, start, lay, c)
    n = len(sims)
    m._cost(x, start, lay, c)
    assert len(sims) == n + 1


def test_the_screen_runs_on_the_first_half_of_each_training_segment():
    """`Campaign.screening`: the same targets cut at half of each run's training segment
    (every other sample, so the first half of each target vector), each normalised by its
    own norm; the models simulate half the samples; the whole-training variant keeps the
    share; built once."""
    from vtable.diagnose.sampling import SCREEN_SHARE, segments

    c = Campaign.of(truth_campaign(*PITCH))
    s = c.screening()
    assert SCREEN_SHARE == 0.5 and s.share == SCREEN_SHARE and c.share == 1.0
    assert s is c.screening() and s.screening() is s
    assert len(s.targets) == len(c.targets)
    for (r, g, y, _), (r2, g2, y2, norm2) in zip(c.targets, s.targets, strict=True):
        assert (r.name, g) == (r2.name, g2)
        n = segments(r)[0].stop
        assert c.train_stop(r) == n and s.train_stop(r) == round(n / 2)
        assert len(y2) == (round(n / 2) + 1) // 2  # every other sample of the first half
        np.testing.assert_array_equal(y2, y[:len(y2)])
        assert norm2 == pytest.approx(np.linalg.norm(y2))
    assert 0.45 < s.n_target / c.n_target < 0.55
    w = s.whole_training()
    assert w.whole and w.share == SCREEN_SHARE
    for r in s.runs:
        assert w.train_stop(r) == round(segments(r, True)[0].stop / 2)
    assert c.whole_training().screening().train_stop(s.runs[0]) == w.train_stop(s.runs[0])


@functools.cache
def friction_fitted():
    """The friction campaign, the model with friction fitted on it, an unfitted estimator on
    its table and declaration, and its screening share: (campaign, fitted, model, share)."""
    c = Campaign.of(truth_campaign(*FRICTION))
    start = Physics(nominal_open_loop(c.table), c.specimen, {"actuator_friction": {}})
    fitted = TableModel(start=start).fit(c)
    model = TableModel()
    model.vt, model.declared, model.campaign_ = c.table, c.specimen, c
    return c, fitted, model, c.training_for(fitted.physics_).screening()


def test_the_round_frame_is_refitted_on_the_screening_share():
    """`Frame.of` on the screening share: the current model (fitted on the whole training
    segments) takes `BASE_STEPS` there first, so the baseline a candidate must beat by 1 %
    is what the base alone reaches on the share — below the fitted model's cost there and
    within 1 % of a converged refit (forward differences, up to 40 steps)."""
    from vtable.diagnose.projected import Frame

    _, fitted, model, share = friction_fitted()
    frame = Frame.of(model, fitted.physics_, share)
    lay = model._layout(fitted.physics_)
    x = model._pack(fitted.physics_, lay)
    lo, hi = model.bounds(lay)
    f0 = model._cost(x, fitted.physics_, lay, share)
    assert frame.cost < float(f0 @ f0)
    full = model._cost(frame.x, fitted.physics_, lay, share)
    assert float(full @ full) == pytest.approx(frame.cost, rel=1e-12)  # its own cost
    ref = scipy.optimize.least_squares(
        lambda z: model._cost(z, fitted.physics_, lay, share),
        np.clip(x, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo)), bounds=(lo, hi),
        diff_step=1e-4, max_nfev=40)
    assert frame.cost <= 1.01 * float(ref.fun @ ref.fun), (frame.cost, float(f0 @ f0),
                                                            float(ref.fun @ ref.fun))
    assert frame.J.shape == (share.n_target, len(lay))


def test_a_backward_refit_far_above_the_model_stops_after_its_first_steps(monkeypatch):
    """A backward step's refit, the model without one effect, under a ceiling of
    `BACKWARD_FACTOR` times the model's cost. The pitch campaign's model without its pitch:
    after `SCREEN_STEPS` least-squares iterations, far above the ceiling, it stops there,
    screened, within 1.5 x what the refit reaches in full (itself ~1000 x the model's: the
    same call), in under half its simulations. The friction campaign's without its
    friction comes below the ceiling (3.5 x): refitted as without one (to rounding)."""
    from vtable.diagnose.model import BACKWARD_FACTOR, refit_without

    evals = [0]
    cost = TableModel._cost

    def counted(self, *a, **kw):
        evals[0] += 1
        return cost(self, *a, **kw)

    monkeypatch.setattr(TableModel, "_cost", counted)

    def refit(c, **kw):
        evals[0] = 0
        return TableModel(**kw).fit(c), evals[0]

    c = Campaign.of(truth_campaign(*PITCH))
    fitted = TableModel(["pitch_flexibility"]).fit(c)
    job = refit_without(fitted.physics_, "pitch_flexibility", fitted.cost_, c)
    assert job["ceiling"] == BACKWARD_FACTOR * fitted.cost_
    screened, n_screened = refit(c, **job)
    full, n_full = refit(c, start=job["start"], choose=False)
    assert screened.screened_ and not full.screened_
    assert full.cost_ > 10 * BACKWARD_FACTOR * fitted.cost_, (full.cost_, fitted.cost_)
    assert full.cost_ <= screened.cost_ <= 1.5 * full.cost_, (screened.cost_, full.cost_)
    assert n_screened < n_full / 2, (n_screened, n_full)
    c, fitted, _, _ = friction_fitted()
    job = refit_without(fitted.physics_, "actuator_friction", fitted.cost_, c)
    under, _ = refit(c, **job)
    full, _ = refit(c, start=job["start"], choose=False)
    assert 2 * fitted.cost_ < full.cost_ < BACKWARD_FACTOR * fitted.cost_
    # (to rounding: the same steps, the residuals of its start read from the screening
    # steps' simulations, which the BLAS may sum in another order at another alignment)
    assert not under.screened_ and under.cost_ == pytest.approx(full.cost_, rel=1e-12)
    assert [p.key for p in under.layout_] == [p.key for p in full.layout_]
    np.testing.assert_allclose(under._pack(under.physics_, under.layout_),
                               full._pack(full.physics_, full.layout_), rtol=1e-9, atol=1e-12)


def test_the_declared_loop_is_linearised_once_a_round_for_every_candidates_start(monkeypatch):
    """Where the fitted servo loop is `FAR` from the declared one, `Frame.of` also takes the
    current model's Jacobian with its loop as declared (the other parameters as fitted):
    it agrees with central differences there (an independent estimate), and a candidate's
    screen started from the declared loop differences only its own parameters (one
    Jacobian a round, not one a candidate). Near the declared loop there is none."""
    from scipy.optimize._numdiff import approx_derivative

    from vtable.diagnose import projected
    from vtable.diagnose.projected import FAR, Frame

    c, fitted, model, share = friction_fitted()
    lay = model._layout(fitted.physics_)
    x = model._pack(fitted.physics_, lay)
    loop = np.array([p.group == "loop" for p in lay])
    declared = np.array([np.log(p.declared) if p.log else p.declared for p in lay])
    near = model._unpack(np.where(loop, declared, x), fitted.physics_, lay)
    assert Frame.of(model, near, share).J_declared is None
    far_x = np.where(loop, declared + 3 * FAR, x)  # a loop that stood in for something
    far = model._unpack(far_x, fitted.physics_, lay)
    frame = Frame.of(model, far, share)
    assert frame.J_declared is not None
    at = np.where(loop, declared, model._pack(far, lay))
    ref = approx_derivative(lambda z: model._cost(z, far, lay, share)[:share.n_target], at,
                            method="3-point", rel_step=1e-4)
    err = np.linalg.norm(frame.J_declared - ref, axis=0) / np.linalg.norm(ref, axis=0)
    assert err.max() < 0.05, err
    assert np.linalg.norm(frame.J_declared - frame.J) > 0.1 * np.linalg.norm(frame.J)

    columns = []  # the columns every forward difference of the screen takes
    at_cols = projected.Secant.at

    def counted(self, z, cols=None):
        columns.append(None if cols is None else len(cols))
        return at_cols(self, z, cols)

    monkeypatch.setattr(projected.Secant, "at", counted)
    monkeypatch.setattr("vtable.diagnose.model.SCREEN", 10.0)  # no start passes: all three
    cand = far.with_effect("force_feedback_filter")
    m = TableModel(start=cand, multistart="force_feedback_filter", frame=frame,
                   baseline=frame.cost, screen_only=True).fit(c)
    assert m.screened_
    own = len(m._layout(cand)) - len(lay)  # the filter's time constant
    assert columns == [own] * 3, columns  # each start differences only the candidate's own


def test_the_workers_compile_the_first_rounds_candidates_as_the_start_is_fitted():
    """`Fits.warm` starts the Dask workers and has each candidate's kernels compiled (or
    loaded) there in tasks that run before the fits submitted later; a model that cannot
    be built is skipped (False), not raised. One worker: nothing to start."""
    from vtable.diagnose.calibration import Calibration
    from vtable.diagnose.pool import Fits
    from vtable.diagnose.workers import _warm

    c = Campaign.of(truth_campaign(*PITCH))
    start = Physics(nominal_open_loop(c.table), c.specimen, {})
    models = [start.with_effect("actuator_friction"),
              start.with_effect("force_feedback_filter"),
              start.with_effect("storey_yield", {"storey": 3})]  # the SDOF frame has one
    assert [_warm(c, ph, ()) for ph in models] == [True, True, False]  # as the task does
    alone = Fits(c, [], 1, Calibration(), TableModel)
    alone.warm(models)
    assert alone.tasks is None
    fits = Fits(c, [], 2, Calibration(), TableModel)
    try:
        fits.warm(models)
        assert fits.tasks is not None and len(fits.tasks._futures) == 3
        assert [f.result(timeout=120) for f in fits.tasks._futures] == [True, True, False]
        done = dict(fits.dispatch([("start", {"start": start})]))  # a fit after them
        assert done["start"].cost > 0
    finally:
        fits.close()


def test_a_freed_core_takes_the_next_fit_in_line_and_one_never_asked_for_is_stopped():
    """`Fits.dispatch(..., ahead=...)`: when one of the fits asked for ends while another
    still runs, the freed core takes the next fit in line at once; a later `dispatch`
    asking for it takes that same run (not submitted again), its result the fit's own to
    the bit (`ahead` a list, or a function asked again as results come); `drop_ahead`
    cancels one never asked for (a running fit reads that from its worker: `StopFlag`),
    the diagnosis's stop event left alone."""
    from distributed import Event

    from vtable.diagnose.calibration import Calibration
    from vtable.diagnose.pool import Fits
    from vtable.diagnose.workers import StopFlag

    c = Campaign.of(truth_campaign(*FRICTION))
    start = Physics(nominal_open_loop(c.table), c.specimen, {})

    def long(e: str) -> dict:  # a candidate's multistart fit: seconds
        return {"start": start.with_effect(e), "multistart": e}

    short = {"start": start, "ceiling": 0.0}  # a few steps, then screened
    fits = Fits(c, [], 2, Calibration(), TableModel)
    try:
        asked = []  # `ahead` as a function: asked again after each result

        def ahead() -> list:
            asked.append(1)
            return [("next", long("valve_dynamics")), ("later", long("oil_column_air"))]

        done = dict(fits.dispatch([("long", long("actuator_friction")), ("short", short)],
                                  ahead=ahead))
        assert set(done) == {"long", "short"} and len(asked) == 1  # once: one core freed
        assert set(fits._ahead) == {"next"}  # one core freed while the other ran: one
        submitted = len(fits.tasks._futures)
        nxt = dict(fits.dispatch([("next", long("valve_dynamics"))]))["next"]
        assert len(fits.tasks._futures) == submitted and not fits._ahead  # the same run
        own = fits.here(long("valve_dynamics"))
        assert nxt.cost == own.cost and nxt.train_error == own.train_error  # to the bit
        # one never asked for: its own event set (the fit stops at its next look), cancelled
        dict(fits.dispatch([("long", long("actuator_friction")), ("short", short)],
                           ahead=[("dropped", long("oil_column_air"))]))
        fut = fits._ahead["dropped"]
        fits.drop_ahead()
        assert not fits._ahead and fut.cancelled()
        # cancelled, not stopped through the diagnosis's event (`StopFlag`'s task state)
        assert not Event(fits.tasks.stop.name).is_set()
        assert not StopFlag(fits.tasks.stop.name).is_set()
        # begun before the round's other work (`begin`): the dispatch takes them over
        fits.begin([("begun", long("valve_dynamics"))])
        submitted = len(fits.tasks._futures)
        begun = dict(fits.dispatch([("begun", long("valve_dynamics"))]))["begun"]
        assert len(fits.tasks._futures) == submitted and not fits._ahead
        assert begun.cost == own.cost and begun.train_error == own.train_error
    finally:
        fits.close()


def _until_stopped(flag, path: str) -> None:
    """A task that writes `path`.started, looks at `flag` every millisecond for up to
    20 s, then writes the time it stopped to `path`."""
    from pathlib import Path

    Path(path + ".started").write_text("")
    t0 = time.monotonic()
    while time.monotonic() - t0 < 20 and not flag.is_set():
        time.sleep(0.001)
    Path(path).write_text(repr(time.time()))


def test_a_cancelled_fit_stops_at_its_next_look_not_at_the_next_message(tmp_path):
    """A task the client cancels (`Tasks.drop`: a fit started ahead and not asked for; or
    Ctrl-C's `halt`) reads that from its worker's own state at its next look at its
    `StopFlag`: it ends within milliseconds, where the Dask event, read every `POLL_S`,
    took up to 0.2 s (a dropped fit held a core of the next round ~0.1 s). Its event is
    never set here; outside a worker the flag reads only its events."""
    import uuid
    from pathlib import Path

    from distributed import Event

    from vtable.diagnose import workers

    client = workers.cluster(2)
    flag = workers.StopFlag(f"vtable-test-{uuid.uuid4().hex}")
    assert not flag.is_set() and not flag._cancelled()  # here, not in a worker
    for k in range(3):
        out = tmp_path / f"stopped{k}"
        fut = client.submit(_until_stopped, flag, str(out), pure=False)
        for _ in range(2000):  # running (a busy worker may take a while to start it),
            if Path(f"{out}.started").exists():  # and its first look at the event made
                break
            time.sleep(0.01)
        assert Path(f"{out}.started").exists(), "the task did not start within 20 s"
        time.sleep(0.05)
        t = time.time()
        client.cancel([fut])
        for _ in range(500):
            if out.exists() and out.read_text():
                break
            time.sleep(0.01)
        assert out.exists(), "the cancelled task did not stop within 5 s"
        late = float(Path(out).read_text()) - t
        assert 0 <= late < 1.0, late  # milliseconds here; never, from the event alone
    assert not Event(flag.name, client=client).is_set()
    # the task is looked up at every look: a flag read by two tasks in turn answers for
    # the one running (the first one's end does not stop the second)
    from types import SimpleNamespace

    class Worker:
        current = "a"
        state = SimpleNamespace(tasks={"a": SimpleNamespace(state="executing")})

        def get_current_task(self):
            if self.current is None:
                raise KeyError("not a task thread")
            return self.current

    shared = workers.StopFlag(flag.name)
    shared._next = float("inf")  # its event not read here
    w = shared._worker = Worker()
    assert not shared.is_set()
    del w.state.tasks["a"]  # the first task done and forgotten, the second running
    w.state.tasks["b"], w.current = SimpleNamespace(state="executing"), "b"
    assert not shared.is_set()
    w.state.tasks["b"].state = "cancelled"
    assert shared.is_set()
    w.current = None  # another thread of the worker: no task of its own
    assert not shared.is_set()


def test_a_fit_asked_to_stop_returns_none_and_its_dispatch_stops():
    """A worker's fit whose stop flag is set returns None (no traceback pickled and sent);
    `Fits.dispatch` meeting one raises `StopRequestedError`, as a fit here does."""
    import threading

    from vtable.diagnose.calibration import Calibration
    from vtable.diagnose.pool import Fits
    from vtable.diagnose.residuals import StopRequestedError
    from vtable.diagnose.workers import _fit

    c = Campaign.of(truth_campaign(*FRICTION))
    start = Physics(nominal_open_loop(c.table), c.specimen, {})
    stop = threading.Event()
    stop.set()
    assert _fit(c, {"start": start}, Calibration(), stop, ()) is None
    fits = Fits(c, [], 2, Calibration(), TableModel)
    try:
        fits.start()
        fits.halt()  # the diagnosis's event set: every worker's fit stops at its first look
        with pytest.raises(StopRequestedError):
            dict(fits.dispatch([("a", {"start": start}), ("b", {"start": start})]))
    finally:
        fits.close()


def test_no_thread_is_writing_a_log_record_when_the_workers_fork():
    """While this process forks (its workers), every log handler's lock is held
    (`workers.hold_logs`, before the fork; `let_logs_go` after it, in this process): no
    other thread is inside a stream's write then, whose lock the child would inherit held
    (a worker hung on its first log line so). A record another thread emits meanwhile waits
    and is written after."""
    import io
    import logging
    import threading

    from vtable.diagnose import workers

    stream = io.StringIO()
    h = logging.StreamHandler(stream)
    lg = logging.getLogger("vtable-test-fork")
    lg.addHandler(h)
    lg.setLevel(logging.INFO)
    try:
        workers.hold_logs()
        assert h in workers._HELD
        t = threading.Thread(target=lg.info, args=("written after the fork",))
        t.start()
        t.join(0.3)
        assert t.is_alive() and stream.getvalue() == ""
        workers.let_logs_go()
        t.join(10)
        assert not t.is_alive() and stream.getvalue() == "written after the fork\n"
        assert not workers._HELD
    finally:
        workers.let_logs_go()
        lg.removeHandler(h)


def test_the_heap_is_frozen_for_the_workers_fork_until_they_end(monkeypatch):
    """The local workers are forked with this process's objects out of the collector's
    sight (`gc.freeze`: the imports' and the campaign's, tens of thousands), given back
    when the cluster ends, or at once when it cannot be made; a freeze of the program's
    own is not ours to undo."""
    import gc

    from vtable.diagnose import workers

    workers.shutdown()
    assert gc.get_freeze_count() == 0
    workers.cluster(2)
    assert gc.get_freeze_count() > 10_000
    workers.shutdown()
    assert gc.get_freeze_count() == 0

    def refused(*a, **k):
        raise OSError("no port")

    monkeypatch.setattr(workers, "LocalCluster", refused)
    with pytest.raises(OSError):
        workers.cluster(2)
    assert gc.get_freeze_count() == 0
    gc.freeze()  # the program's own
    try:
        workers.shutdown()
        assert gc.get_freeze_count() > 10_000
    finally:
        gc.unfreeze()


def test_the_amplitude_screen_tells_friction_from_a_missing_linear_effect():
    """On the starting model's residual: the table's pitch missing (linear) leaves the same
    residual H1 in every run, z below `Z_SCREEN` (measured 9.1: the random runs against the
    earthquake, whose spectra differ); 3 kip of friction does not (measured 156)."""
    z = {}
    for name, (effects, pitch) in (("pitch", PITCH), ("friction", FRICTION)):
        c = Campaign.of(truth_campaign(effects, pitch))
        m = TableModel().fit(c)
        ev = nonlinearity_evidence(c, m.predictions(c))
        z[name] = ev.amplitude
        assert ev.pairs >= 10 and ev.spread > 1.2
    assert z["pitch"] < Z_SCREEN, z
    assert z["friction"] > 10 * Z_SCREEN, z


def test_a_linear_fit_that_leaves_no_amplitude_dependence_explains_it():
    """`linear_explains` (a model nonlinear itself): of the fits handed to it, the one with
    the lowest training cost is read. On the friction campaign, the bare model's fit
    leaves plenty of amplitude dependence (''); a prediction that leaves only white noise
    (1 % of each channel's RMS) none (the reason names its effect, with the current
    model's z); a fit without a finite cost is not read."""
    c = Campaign.of(truth_campaign(*FRICTION))
    bare = TableModel().fit(c)
    bad = bare.predictions(c)
    before = nonlinearity_evidence(c, bad)
    assert before.read and before.amplitude > 10 * Z_SCREEN
    rng = np.random.default_rng(3)
    good = {r.name: {ch: y + 0.01 * np.std(y) * rng.standard_normal(len(y))
                     for ch, y in r.channels.items()} for r in c.runs}
    assert not nonlinearity_evidence(c, good).present
    why = linear_explains(c, before, [(1.0, "valve_dynamics", good),
                                      (2.0, "sensor_filter", bad)])
    assert "but with valve_dynamics fitted" in why and "no longer beyond the noise" in why, why
    assert f"({before.amplitude:.1f} standard deviations)" in why
    assert linear_explains(c, before, [(2.0, "valve_dynamics", good),
                                       (1.0, "sensor_filter", bad)]) == ""
    assert linear_explains(c, before, [(np.nan, "valve_dynamics", good)]) == ""
    assert linear_explains(c, before, []) == ""


@functools.cache
def diagnosis(which: str):
    effects, pitch = {"pitch": PITCH, "friction": FRICTION}[which]
    runs = truth_campaign(effects, pitch)
    t0 = time.perf_counter()
    d = Diagnoser(runs, catalog=BUILT_IN).diagnose()  # other tests may register effects
    return d, time.perf_counter() - t0


def test_a_linear_campaign_keeps_the_nonlinear_candidates_out():
    """Pitch missing: every nonlinear candidate is kept out by the screen (not fitted, its
    reason in the evidence), the linear ones screened or refined; pitch_flexibility found,
    and the final error is the plain fit's of the same model (to 0.05 % NRMS)."""
    d, _ = diagnosis("pitch")
    assert d.final_effects == ["pitch_flexibility"], d.verdict
    first = d.rounds[0]
    nonlinear = {"valve_flow_nonlinearity", "actuator_friction", "flow_saturation",
                 "oil_column_air", "amplitude_dependent_damping", "storey_yield"}
    # every catalog effect ranked, but the mount the runs' table channels show none of, the
    # zero offset no mean acceleration shows and the degradation no moving notch shows
    assert {c.effect for c in first.ranking} == set(BUILT_IN) - {
        "sensor_mount", "sensor_offset", "specimen_degradation"}
    assert "the runs show no mount" in first.skipped["sensor_mount"]
    assert "the runs show no offset" in first.skipped["sensor_offset"]
    assert "no change of the specimen" in first.skipped["specimen_degradation"]
    for c in first.ranking:
        if c.effect in nonlinear:
            assert c.not_fitted and "no amplitude dependence" in c.evidence, c.effect
        else:
            assert not c.not_fitted, c.effect
    plain = TableModel(["pitch_flexibility"]).fit(truth_campaign(*PITCH))
    assert d.final_error == pytest.approx(plain.score(), abs=5e-4)


def test_friction_is_found_with_the_nonlinear_candidates_fitted():
    d, _ = diagnosis("friction")
    assert d.final_effects == ["actuator_friction"], d.verdict
    ranked = {c.effect: c for c in d.rounds[0].ranking}
    assert not any(c.not_fitted for c in ranked.values())  # amplitude dependence: all tried
    assert ranked["actuator_friction"].params["friction"] == pytest.approx(3.0, rel=0.1)
    # the truth's runs measure A·ΔP and do not say so: read so once friction is in
    assert d.force_reading["found"] == "delta_p" and d.final.force_measured == "delta_p"
    c = Campaign.of(truth_campaign(*FRICTION))
    start = Physics(nominal_open_loop(c.table), c.specimen, {}, force_measured="delta_p")
    plain = TableModel(["actuator_friction"], start=start).fit(c)
    assert d.final_error == pytest.approx(plain.score(), abs=5e-4)


def test_a_round_starts_with_the_candidates_whose_screen_passed_in_the_last(monkeypatch,
                                                                          tmp_path):
    """The README's friction campaign (friction hidden; the table's pitch and RC filter the
    bare model lacks): the candidate that wins a later round is the one whose screen
    passed, best, in the round before, and its fit (refined in its screen's task, the
    round's longest) is the first screen dispatched, so that no core waits for it at the
    round's end (ordered by what the last round's fits cost, it was dispatched third). In
    the last round, with friction in and no amplitude dependence left, the linear
    candidates are fitted all the same (they were not, as nonlinear models). A round's
    backward refits are on the cores before its frame is taken (`Fits.begin`); the frames
    of the rounds after the first are made by the workers, with the fit of the effect each
    adds, to the bit as this process would make them."""
    from readme_campaigns import campaign

    from vtable.diagnose import pool

    runs = [read_run(p) for p in campaign("actuator_friction", 0.01, tmp_path)]
    screens: list[list[str]] = []  # each dispatch's screen jobs, in order
    dispatch = pool.Fits.dispatch

    def recorded(self, jobs, **kw):
        screens.append([name for (kind, name), _ in jobs if kind == "screen"])
        return dispatch(self, jobs, **kw)

    monkeypatch.setattr(pool.Fits, "dispatch", recorded)
    d = Diagnoser(runs, catalog=BUILT_IN, workers=2)
    promised = []  # each round's `promise`: the round before's passed screens
    fit = d._candidates

    def candidates(*a, **kw):
        promised.append(dict(d.promise))
        return fit(*a, **kw)

    monkeypatch.setattr(d, "_candidates", candidates)
    from vtable.diagnose import engine

    begun: list[set] = []  # the refits running as each round's frame is taken
    frames: list[tuple] = []  # (the model, its frame) of each round
    made_here = []  # the frames this process made
    frame_of, take = engine.Frame.of, d._frame

    def made(*a, **kw):
        made_here.append(a[1])
        return frame_of(*a, **kw)

    def frame(current):
        begun.append({name for kind, name in d.fits._ahead if kind == "without"})
        frames.append((current, take(current)))
        return frames[-1][1]

    monkeypatch.setattr(engine.Frame, "of", made)
    monkeypatch.setattr(d, "_frame", frame)
    dropped: list = []  # the keys of the fits started ahead and dropped by name
    drop_ahead = pool.Fits.drop_ahead

    def drop(self, keys=None):
        if keys:
            dropped.append(sorted(keys))
        return drop_ahead(self, keys)

    monkeypatch.setattr(pool.Fits, "drop_ahead", drop)
    result = d.diagnose()
    assert sorted(result.final_effects) == ["actuator_friction", "force_feedback_filter",
                                            "pitch_flexibility"], result.verdict
    # each round's backward refits (without each effect added before the last) are
    # submitted to the workers before this process makes the round's frame
    added = [r.added for r in result.rounds]
    assert begun == [set(added[:k - 1]) if k > 1 else set() for k in range(len(begun))], \
        (begun, added)
    # the first round's frame (the starting model's) made here; each later round's brought
    # by the fit of the effect it adds, made in its worker beside the round's other fits:
    # to the bit the frame this process makes of that model
    assert len(frames) == len(result.rounds) and made_here == [frames[0][0]], made_here
    for current, f in frames[1:]:
        here = d._model().frame_of(current, d.campaign)
        assert f.keys == here.keys and f.cost == here.cost
        for a in ("x", "Q", "R", "J", "J_declared"):
            assert (getattr(f, a) is None) == (getattr(here, a) is None), a
            if getattr(f, a) is not None:
                assert np.array_equal(getattr(f, a), getattr(here, a)), a
    rounds = [s for s in screens if s]
    added = [r.added for r in result.rounds]
    for k in (1, 2):  # the second and third rounds
        left = {e: v for e, v in promised[k].items() if e not in added[:k]}
        assert min(left, key=left.get) == added[k], (k, promised[k], added)
        assert rounds[k][0] == added[k], (k, rounds[k])
    # the third round: with friction in and the RC filter missing, the residual depends on
    # amplitude (z 31.5 measured), through the friction: the nonlinear candidates were held
    # back, not dispatched with the linear ones, and not fitted once the filter's fit left
    # no amplitude dependence (the fits of theirs an idle core may have started: dropped)
    third = {c.effect: c for c in result.rounds[2].ranking}
    assert d.screens[2].present and d.screens[2].amplitude > Z_SCREEN
    held = {e for e, c in third.items() if c.not_fitted}
    assert held == {"valve_flow_nonlinearity", "flow_saturation", "oil_column_air",
                    "amplitude_dependent_damping", "storey_yield"}, third
    assert not held & set(rounds[2]), rounds[2]
    for e in held:
        assert "but with force_feedback_filter fitted" in third[e].evidence and \
            f"({d.screens[2].amplitude:.1f} standard" in third[e].evidence
    assert dropped == [sorted(("screen", e) for e in held)], dropped
    # ranked in catalog order among themselves, whatever order their fits ran in
    kept = [c.effect for c in result.rounds[2].ranking if c.not_fitted]
    assert kept == sorted(kept, key=BUILT_IN.index), kept
    # the last round's residual shows no amplitude dependence: with friction in, the
    # nonlinear candidates are not fitted, the linear ones are (their models are
    # nonlinear only by the friction they join)
    last = result.rounds[-1]
    assert not d.screens[-1].present
    linear = {"valve_dynamics", "foundation_compliance", "platen_resonator", "sensor_filter"}
    ranked = {c.effect: c for c in last.ranking}
    assert linear <= set(ranked) and not any(ranked[e].not_fitted for e in linear)
    assert all(c.not_fitted for e, c in ranked.items() if e not in linear | {"sensor_mount"})


def test_held_nonlinear_candidates_are_fitted_where_no_linear_fit_explains_the_amplitude(
        monkeypatch, tmp_path):
    """The README's friction campaign with `linear_explains` finding no linear fit that
    leaves the amplitude dependence (as where a second nonlinearity is missing): the third
    round's held nonlinear candidates are dispatched after the linear ones, in a dispatch
    of their own, and fitted; the same effects are found."""
    from readme_campaigns import campaign

    from vtable.diagnose import engine, pool

    runs = [read_run(p) for p in campaign("actuator_friction", 0.01, tmp_path)]
    monkeypatch.setattr(engine, "linear_explains", lambda *a: "")
    screens: list[set[str]] = []  # each dispatch's screen jobs
    dispatch = pool.Fits.dispatch

    def recorded(self, jobs, **kw):
        screens.append({name for (kind, name), _ in jobs if kind == "screen"})
        return dispatch(self, jobs, **kw)

    monkeypatch.setattr(pool.Fits, "dispatch", recorded)
    d = Diagnoser(runs, catalog=BUILT_IN, workers=2)
    result = d.diagnose()
    assert sorted(result.final_effects) == ["actuator_friction", "force_feedback_filter",
                                            "pitch_flexibility"], result.verdict
    third = {c.effect: c for c in result.rounds[2].ranking}
    nonlinear = {"valve_flow_nonlinearity", "flow_saturation", "oil_column_air",
                 "amplitude_dependent_damping", "storey_yield"}
    assert d.screens[2].present and nonlinear <= set(third), third
    assert not any(third[e].not_fitted for e in nonlinear), third
    # the third round's linear screens, then its held nonlinear ones in a dispatch of their own
    rounds = [s for s in screens if s]
    assert nonlinear.isdisjoint(rounds[2]) and rounds[3] == nonlinear, rounds


def test_an_effect_is_nonlinear_by_what_it_brings_not_by_the_model_it_joins():
    """Every catalog effect: nonlinear on a model that already has friction (its own
    force element, damper or stage: `ReducedModel.nonlinear_parts`) exactly when the bare
    model with it alone is not linear."""
    d = Diagnoser(truth_campaign(*PITCH), catalog=BUILT_IN, workers=1)
    friction = d.start.with_effect("actuator_friction")
    assert not d._linear(friction)
    for e in sorted(BUILT_IN):
        if e == "actuator_friction" or d._inapplicable(friction.with_effect(e)):
            continue
        assert d._nonlinear(friction, e) == (not d._linear(d.start.with_effect(e))), e


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_dask_scheduler_of_separate_processes_gives_the_same_diagnosis():
    """`--scheduler`: a Dask scheduler and two workers started as their own processes (as a
    lab's cluster is), the candidates fitted there: the same effects and final error as on
    the local cluster. A scheduler that does not answer is one line."""
    port = _free_port()
    addr = f"tcp://127.0.0.1:{port}"
    exe = [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
           "--port", str(port), "--dashboard-address", ":0"]
    procs = [subprocess.Popen(exe, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        time.sleep(2.0)
        for _ in range(2):
            procs.append(subprocess.Popen(
                [sys.executable, "-m", "distributed.cli.dask_worker", addr, "--nthreads", "1",
                 "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        time.sleep(3.0)
        runs = truth_campaign(*PITCH)
        remote = Diagnoser(runs, catalog=BUILT_IN, scheduler=addr).diagnose()
        local, _ = diagnosis("pitch")
        assert remote.final_effects == local.final_effects
        assert remote.final_error == pytest.approx(local.final_error, rel=1e-6)
    finally:
        for p in procs:
            p.terminate()
        for p in procs:
            p.wait(timeout=30)
    with pytest.raises(VtableError, match="no Dask scheduler answers there") as e:
        Diagnoser(runs, scheduler=f"tcp://127.0.0.1:{_free_port()}").diagnose()
    assert "\n" not in str(e.value)
