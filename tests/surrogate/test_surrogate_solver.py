"""The least-squares machinery of issue 17: analytic Jacobian, Levenberg–Marquardt in lockstep
with losing starts stopped, the block-mapped IPOPT problem, the covariance from the R factor,
the vectorised denominators.

Oracles: central finite differences of the residual (Jacobian), CasADi's automatic
differentiation of the same residual written with CasADi symbols, numpy's SVD of the whole
Jacobian (covariance), ``polynomials`` evaluated temperature by temperature, a known noise-free
model (recovered parameters).
"""

import numpy as np
import pytest

from surrogate import RationalModel, Scaling, Structure
from surrogate._lsq import STATUS_STOPPED, Evaluator, LevenbergMarquardt
from surrogate._nlp import BLOCK_LINES, Problem, Solver, covariance, residual
from surrogate._structure import CasadiBackend, denominators, polynomials

CASES = [("coefficients", 2, 3, 0), ("coefficients", 3, 3, 2), ("sections", 4, 4, 0),
         ("sections", 1, 2, 3), ("sections", 2, 5, 0), ("zpk", 3, 3, 2), ("zpk", 4, 4, 1),
         ("zpk", 2, 3, 0), ("zpk", 0, 1, 0), ("zpk:monic", 3, 3, 2), ("zpk:monic", 2, 3, 0)]


def _structure(form, m, n, deg):
    """``Structure``; "zpk:monic": the zpk zero sections of schema 1 (s̃² + c1 s̃ + c0)."""
    return Structure(*form.split(":")[:1], m, n, deg, *form.split(":")[1:])


def _problem(form, m, n, deg, kind, n_lines=37, seed=0):
    rng = np.random.default_rng(seed)
    st = _structure(form, m, n, deg)
    w = np.geomspace(0.1, 10.0, n_lines)
    tau = rng.uniform(-1, 1, n_lines) if deg else np.zeros(n_lines)
    h = (1 + 0.3 * rng.normal(size=n_lines)) * np.exp(1j * rng.normal(size=n_lines))
    return Problem(st, w, tau, h, kind, rng.uniform(0.5, 2, n_lines), rng.uniform(0.5, 2, n_lines))


@pytest.mark.parametrize("form, m, n, deg", CASES)
@pytest.mark.parametrize("kind", ["log", "relative"])
def test_jacobian_matches_finite_differences_and_casadi(form, m, n, deg, kind):
    import casadi as ca

    pr = _problem(form, m, n, deg, kind)
    st = pr.structure
    theta = np.random.default_rng(1).normal(scale=0.4, size=st.n_params)
    ev = Evaluator(pr)
    r, jac = ev.residual(theta, jacobian=True)
    np.testing.assert_allclose(r, pr.residual(theta), rtol=0, atol=1e-12)
    fd = np.empty_like(jac)
    for i in range(st.n_params):
        step = 1e-6 * max(1.0, abs(theta[i]))
        tp, tm = theta.copy(), theta.copy()
        tp[i] += step
        tm[i] -= step
        fd[:, i] = (ev.residual(tp) - ev.residual(tm)) / (2 * step)
    np.testing.assert_allclose(jac, fd, rtol=0, atol=1e-6 * np.max(np.abs(jac)))
    x = ca.SX.sym("x", st.n_params)
    rs = residual(st, x, pr.w, pr.tau, pr.h.real, pr.h.imag, pr.inv_sig_a, pr.inv_sig_b, kind,
                  CasadiBackend())
    ad = np.asarray(ca.Function("j", [x], [ca.jacobian(rs, x)])(theta), float)
    np.testing.assert_allclose(jac, ad, rtol=0, atol=1e-12 * np.max(np.abs(ad)))
    # a stack of parameter vectors gives the stack of Jacobians
    r2, j2 = ev.residual(np.stack([theta, 0.5 * theta]), jacobian=True)
    np.testing.assert_allclose(r2[0], r, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(j2[1], ev.residual(0.5 * theta, jacobian=True)[1], rtol=1e-14, atol=1e-14)


def _noise_free(st, theta_true, n_lines=60):
    from surrogate._structure import response

    w = np.geomspace(0.05, 20.0, n_lines)
    tau = np.zeros(n_lines)
    return Problem(st, w, tau, response(st, theta_true, w, tau), "log", np.ones(n_lines), np.ones(n_lines))


def test_lockstep_recovers_a_noise_free_model_and_stops_the_beaten_start():
    st = Structure("sections", 2, 3, 0)
    truth = np.array([1.0, 0.5, 0.2, np.log(0.3), np.log(1.0), np.log(2.0)])
    pr = _noise_free(st, truth)
    ev = Evaluator(pr)
    lb, ub = st.bounds(float(pr.w.min()), float(pr.w.max()))
    near = truth + 0.05
    # all poles far above the band and a flat numerator: a poor, slow start
    far = np.array([1.0, 0.0, 0.0, np.log(40.0), np.log(400.0), np.log(20.0)])
    lm = LevenbergMarquardt(ev, np.stack([near, far]), lb, ub, 1e-12).run(300)
    assert lm.converged[0] and lm.status[1] == STATUS_STOPPED and not lm.converged[1]
    assert lm.cost[1] > lm.cost[0]
    np.testing.assert_allclose(lm.theta[0], truth, rtol=0, atol=1e-6)
    assert lm.iterations[1] == lm.iterations[0]        # stopped when the other converged
    # revived, the stopped start runs on (and is never stopped again)
    before = lm.cost[1]
    lm.revive(1)
    lm.run(1000, only=[1])
    assert lm.cost[1] < before and lm.status[1] != STATUS_STOPPED


def test_a_start_with_a_margin_keeps_running():
    st = Structure("sections", 2, 3, 0)
    truth = np.array([1.0, 0.5, 0.2, np.log(0.3), np.log(1.0), np.log(2.0)])
    pr = _noise_free(st, truth)
    lm = LevenbergMarquardt(Evaluator(pr), np.stack([truth, truth + 0.3]), *st.bounds(0.05, 20.0), 1e-12)
    lm.run(500)
    # the exact start converges at once; the other, far above it then, is stopped …
    assert lm.converged[0] and lm.cost[0] < 1e-20
    assert lm.status[1] == STATUS_STOPPED
    lm2 = LevenbergMarquardt(Evaluator(pr), np.stack([truth, truth + 0.3]), *st.bounds(0.05, 20.0), 1e-12,
                             margins=[0.0, np.inf])
    lm2.run(500)
    assert lm2.converged[1]                    # … unless its margin lets it run (a warm start)
    np.testing.assert_allclose(lm2.theta[1], truth, rtol=0, atol=1e-6)


@pytest.mark.parametrize("n_lines", [BLOCK_LINES - 1, 3 * BLOCK_LINES + 5])
def test_block_mapped_ipopt_problem_agrees_with_levenberg_marquardt(n_lines):
    st = Structure("zpk", 2, 3, 1)
    rng = np.random.default_rng(5)
    w = np.geomspace(0.1, 10.0, n_lines)
    tau = rng.uniform(-1, 1, n_lines)
    truth = np.array([1.5, 0.2, -0.5, 0.1, 0.12, 0.1, np.log(0.4), -0.1, 0.0, -0.15, np.log(0.3), 0.1])
    from surrogate._structure import response

    h = response(st, truth, w, tau) * np.exp(0.01 * (rng.normal(size=n_lines) + 1j * rng.normal(size=n_lines)))
    pr = Problem(st, w, tau, h, "log", np.full(n_lines, 100.0), np.full(n_lines, 100.0))
    out = Solver(st, n_lines, "log", grid_taus=np.linspace(-1, 1, 11)).solve(pr, truth + 0.02)
    assert out.converged
    assert out.cost == pytest.approx(pr.cost(out.theta), rel=1e-12)   # padding lines add nothing
    lm = LevenbergMarquardt(Evaluator(pr), truth + 0.02, *st.bounds(), 1e-12).run(300)
    assert lm.converged[0]
    assert out.cost == pytest.approx(lm.cost[0], rel=1e-8)
    np.testing.assert_allclose(out.theta, lm.theta[0], rtol=0, atol=1e-5)


@pytest.mark.parametrize("shape, spread", [((120, 9), 0.0), ((4000, 21), 6.0), ((500, 6), 10.0)])
def test_covariance_from_the_r_factor_equals_the_svd_of_the_jacobian(shape, spread):
    rng = np.random.default_rng(6)
    jac = rng.normal(size=shape) * np.logspace(0, spread, shape[1])
    r = rng.normal(size=shape[0])
    cov, deficient = covariance(jac, r, True)
    _, s, vt = np.linalg.svd(jac, full_matrices=False)
    ref = (vt.T / s ** 2) @ vt * (r @ r) / (shape[0] - shape[1])
    sd = np.sqrt(np.diag(ref))
    np.testing.assert_allclose(cov / np.outer(sd, sd), ref / np.outer(sd, sd), rtol=0, atol=1e-6)
    assert not deficient
    jac[:, -1] = jac[:, 0]                                   # exactly dependent columns
    assert covariance(jac, r, True)[1]


@pytest.mark.parametrize("form, m, n, deg", CASES)
def test_vectorised_denominators_equal_polynomials_per_temperature(form, m, n, deg):
    st = _structure(form, m, n, deg)
    theta = np.random.default_rng(2).normal(scale=0.5, size=st.n_params)
    taus = np.linspace(-1.2, 1.2, 9)
    ref = np.array([polynomials(st, theta, t)[1] for t in taus])
    np.testing.assert_allclose(denominators(st, theta, taus), ref, rtol=1e-13, atol=1e-13)



def test_joint_zpk_fourth_order_converges_at_five_temperatures():
    """Seed 001's physics at 5 temperatures (60 lines, 0.2 dB / 1°): IPOPT ran out of 3756
    iterations here (issue 17); the joint fit must converge and predict temperatures between
    the fitted ones within the one-line noise floor (~0.029)."""
    import physmodel
    from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
    from surrogate import ScheduledFit, relative_rms_error

    model = physmodel.ActuatorModel(physmodel.get_parameter_set("seed001_actuator"))
    f_hz = np.geomspace(0.1, 9.0, 60)
    sweep = synthesize_sweep(model, "M", f_hz, [19.0, 28.0, 37.0, 46.0, 55.0], MagnitudePhaseNoise(0.2, 1.0), seed=1)
    res = ScheduledFit("zpk", 4, 4, 2).fit(sweep)           # raises if not converged
    assert res.stability.stable
    for temp in (26.3, 39.7, 48.1):
        exact = synthesize_sweep(model, "M", f_hz, [temp], None).response
        assert relative_rms_error(res.model.frequency_response(f_hz, temp), exact) < 0.02


def test_reported_errors_equal_the_saved_models_own_response():
    """finish() takes the model's response from the residual model (R · H_data); it must be
    what the fitted RationalModel itself evaluates."""
    from surrogate_fixtures import FIT_TEMPS, TRUE_SCALING, TRUE_THETA, noisy_sweep

    from surrogate import RationalFit, RationalModel, ScheduledFit, fit_percent, relative_rms_error

    truth = RationalModel(Structure("zpk", 2, 3, 2), TRUE_THETA, TRUE_SCALING, (19.0, 55.0))
    f, t, h, sm, sp = noisy_sweep(truth, FIT_TEMPS, np.geomspace(0.1, 30, 40))
    res = ScheduledFit("zpk", 2, 3, 2).fit(f, t, h, sm, sp)
    for e in res.per_temperature:
        k = t == e.temperature_c
        hm = res.model.frequency_response(f[k], e.temperature_c)
        assert e.relative_rms_error == pytest.approx(relative_rms_error(hm, h[k]), rel=1e-12)
        assert e.fit_percent == pytest.approx(fit_percent(hm, h[k]), rel=1e-12)
    k = t == FIT_TEMPS[0]
    one = RationalFit(2, 3).fit(f[k], None, h[k])
    assert one.per_temperature[0].relative_rms_error == pytest.approx(
        relative_rms_error(one.model.frequency_response(f[k]), h[k]), rel=1e-12)


def _noisy_sections_problem():
    from surrogate._structure import response

    st = Structure("sections", 2, 3, 0)
    truth = np.array([1.0, 0.5, 0.2, np.log(0.3), np.log(1.0), np.log(2.0)])
    n_lines = 60
    w = np.geomspace(0.05, 20.0, n_lines)
    tau = np.zeros(n_lines)
    rng = np.random.default_rng(1)
    h = response(st, truth, w, tau) * np.exp(0.01 * (rng.normal(size=n_lines) + 1j * rng.normal(size=n_lines)))
    return st, truth, Problem(st, w, tau, h, "log", np.ones(n_lines), np.ones(n_lines))


def test_a_trailing_start_is_stopped_before_the_leader_converges_and_the_leader_is_unchanged():
    st, truth, pr = _noisy_sections_problem()
    ev = Evaluator(pr)
    lb, ub = st.bounds(float(pr.w.min()), float(pr.w.max()))
    # the leader needs 15 iterations; the other start (poles far above the band) trails it
    starts = np.stack([truth + 0.5, np.array([1.0, 0.0, 0.0, np.log(40.0), np.log(400.0), np.log(20.0)])])
    plain = LevenbergMarquardt(ev, starts, lb, ub, 1e-12).run(500)
    lm = LevenbergMarquardt(ev, starts, lb, ub, 1e-12, trailing_ratio=2.0).run(500)
    assert plain.converged[0] and lm.converged[0] and lm.status[1] == STATUS_STOPPED
    assert lm.iterations[1] < lm.iterations[0] == plain.iterations[0]     # stopped before the end
    assert lm.cost[1] > 2.0 * lm.cost[0]
    # the starts advance independently in lockstep: stopping one leaves the other's path (up to
    # the summation order of a stack of one instead of two)
    np.testing.assert_allclose(lm.theta[0], plain.theta[0], rtol=1e-12, atol=0)
    assert lm.cost[0] == pytest.approx(plain.cost[0], rel=1e-13)


@pytest.mark.parametrize("rate, stopped", [(0.0, True), (0.1, True), (0.5, False)])
def test_the_trailing_rule_lets_a_start_through_that_closes_the_gap_in_time(rate, stopped):
    """Leader at cost 1 (flat), the other at 3: gap 2; closing at ``rate`` per accepted step it
    needs 2/rate iterations, stopped above CATCH_UP_ITERATIONS (10)."""
    st, truth, pr = _noisy_sections_problem()
    lm = LevenbergMarquardt(Evaluator(pr), np.stack([truth, truth + 0.1]), *st.bounds(0.05, 20.0), 1e-12,
                            trailing_ratio=2.0)
    w = lm.CATCH_UP_WINDOW
    lm.cost[:] = [1.0, 3.0]
    lm.traces = [[1.0] * (w + 1), [3.0 + rate * (w - k) for k in range(w + 1)]]
    assert lm._stop_trailing() is stopped
    assert (lm.status[1] == STATUS_STOPPED) is stopped and lm.running[0]


def test_unit_zero_section_bounds_keep_zeros_away_from_the_origin():
    """'zpk' slot bounds with a band: |β2| ≤ 1/z², |β1| ≤ 2/z, |β| ≤ 1/z (z = w_min/1000) keep every
    zero at |s̃| ≥ z/(1 + √2) (roots of μ² + β1 μ + β2 have |μ| ≤ |β1|/2 + √(β1²/4 + |β2|)), and
    a zero at infinity (β = 0) inside them."""
    st = Structure("zpk", 3, 3, 0)
    w_min, w_max = 0.1, 10.0
    b = st.slot_bounds(w_min, w_max)
    z = w_min / 1e3
    assert b["zb2_0"] == pytest.approx((-1 / z ** 2, 1 / z ** 2)) and b["zb1_0"] == pytest.approx((-2 / z, 2 / z))
    assert b["zb"] == pytest.approx((-1 / z, 1 / z)) and b["zb"][0] < 0.0 < b["zb"][1]
    rng = np.random.default_rng(7)
    for _ in range(200):
        theta = np.concatenate([[1.0], rng.uniform(*zip(b["zb1_0"], b["zb2_0"], b["zb"])), np.zeros(3)])
        theta[1:4] *= rng.choice([1.0, 1e-3, 1e-9])              # also zeros far out
        zeros = RationalModel(st, theta, Scaling(1.0, 1.0)).zeros()
        assert np.all(np.abs(zeros) >= z / (1 + np.sqrt(2)) * (1 - 1e-12))
    monic = Structure("zpk", 3, 3, 0, "monic").slot_bounds(w_min, w_max)      # schema-1 sections
    assert monic["zc0_0"] == pytest.approx((-(w_max * 1e3) ** 2, (w_max * 1e3) ** 2))
