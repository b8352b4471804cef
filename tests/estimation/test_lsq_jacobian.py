"""The calibration engine's Jacobian and the array path that feeds it.

Oracles, none of them the code under test:

* the states of parameter sets built one by one (``apply_values`` + ``state_at``, the reference
  path) for :class:`~physmodel.parameter_paths.StateMap`;
* Richardson-extrapolated central differences of the residuals computed through that reference
  path (a parameter set per point, ``ActuatorModel``), with a step-size study showing that the
  oracle has converged, for the engine's batched forward-difference Jacobian, whose own error must
  shrink in proportion to its step (a forward difference of the right function);
* the stationarity of the reference residuals (Gauss–Newton step from the oracle Jacobian) at the
  calibrated estimate, for the engine's stopping rules.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from physmodel import ActuatorModel, get_parameter_set
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from physmodel.estimation.calibration import calibrate, default_free_parameter, physics_predictor
from physmodel.estimation.lsq import fit_parameters, residual_jacobian
from physmodel.estimation.observations import ScalarObservations
from physmodel.estimation.records import FreeParameter
from physmodel.estimation.residuals import residuals
from physmodel.parameter_paths import StateMap, apply_values
from physmodel.params import STATE_FIELDS, state_at
from physmodel.temperature import Arrhenius, Linear, LogLinear

FREE = ["d", "kappa_e", "alpha0", "E", "xi", "r1_sheet", "laws.d.activation_energy", "laws.E.slope"]
TEMPS = np.array([5.0, 30.0, 55.0, 75.0])
FREQS = np.logspace(-1, 2, 25)


@pytest.fixture(scope="module")
def problem():
    base = get_parameter_set("seed002_table3")
    truth = replace(base.replace(d=4.2e-11, kappa_e=3.9e-7, alpha0=base.alpha0 * 1.15, E=1.7e8, xi=0.21,
                                 r1_sheet=80.0),
                    laws=base.laws.with_(d=Arrhenius(19e3), E=LogLinear(-0.009)))
    sw = synthesize_sweep(ActuatorModel(truth), "M", FREQS, TEMPS, noise=MagnitudePhaseNoise(0.1, 1.0), seed=5)
    free = [default_free_parameter(base, n) for n in FREE]
    return base, truth, sw, free


def _rows_in_box(free, n, seed):
    rng = np.random.default_rng(seed)
    lo = np.array([fp.z_bounds[0] for fp in free])
    hi = np.array([fp.z_bounds[1] for fp in free])
    Z = lo + rng.random((n, len(free))) * (hi - lo)
    return np.array([[float(fp.from_z(z)) for fp, z in zip(free, row)] for row in Z])


# ------------------------------------------------------------------------------ states as arrays
def test_state_map_matches_sets_built_one_by_one(problem):
    base, _, sw, free = problem
    smap = StateMap.build(base, FREE, [fp.lower for fp in free], [fp.upper for fp in free],
                          [fp.initial for fp in free], TEMPS)
    assert smap is not None
    X = _rows_in_box(free, 12, seed=1)
    got = smap(X)
    ref = state_at([apply_values(base, dict(zip(FREE, row))) for row in X], TEMPS)
    for f in STATE_FIELDS:
        a, b = getattr(got, f), getattr(ref, f)
        assert a.shape == b.shape == (12, TEMPS.size, 1)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=0, err_msg=f)


def test_state_map_columns_are_its_states(problem):
    # the oracle: the map's own states (checked against state_at above), field by field
    base, _, _, free = problem
    smap = StateMap.build(base, FREE, [fp.lower for fp in free], [fp.upper for fp in free],
                          [fp.initial for fp in free], TEMPS)
    for n_rows in (7, 1, 7):                 # the second 7: the fixed columns kept for that count
        X = _rows_in_box(free, n_rows, seed=n_rows)
        st = smap(X)
        p, rows, differ = smap.columns(X)
        assert rows == n_rows and sorted(p) == sorted(STATE_FIELDS)
        for f in STATE_FIELDS:
            assert p[f].shape == (n_rows * TEMPS.size, 1)
            assert np.array_equal(p[f].reshape(n_rows, TEMPS.size, 1), getattr(st, f)), f
            if f not in differ:             # the same in every row, and not writable
                assert np.array_equal(getattr(st, f), np.broadcast_to(getattr(st, f)[:1], getattr(st, f).shape))
                assert not p[f].flags.writeable
    assert {"d", "kappa_e", "alpha0", "E", "xi", "r1"} <= set(differ) and "L" not in differ


def test_state_map_refuses_what_is_not_log_affine(problem):
    base, _, _, _ = problem
    linear_law = replace(base, laws=base.laws.with_(r1_sheet=Linear(2e-3)))
    # a linear law's alpha: 1 + alpha (T - T_ref) is not exponential in alpha
    assert StateMap.build(linear_law, ["laws.r1_sheet.alpha"], [-5e-3], [5e-3], [2e-3], TEMPS) is None
    # a coupling whose box contains zero: ln|alpha0| is undefined there
    assert StateMap.build(base, ["alpha0"], [-3.0], [1.0], [base.alpha0], TEMPS) is None
    # ... and calibration still runs, through parameter sets built one by one
    sw = synthesize_sweep(ActuatorModel(replace(linear_law, laws=linear_law.laws.with_(r1_sheet=Linear(3e-3)))),
                          "M", FREQS, [10.0, 60.0], noise=MagnitudePhaseNoise(0.1, 1.0), seed=2)
    res = calibrate(sw, linear_law, [FreeParameter("laws.r1_sheet.alpha", -5e-3, 5e-3), "d"], starts=1)
    assert res.converged and res.n_model_calls > 0


def test_array_and_per_set_paths_give_the_same_fit(problem):
    base, _, sw, _ = problem
    free = [default_free_parameter(base, n) for n in ("d", "alpha0", "laws.d.activation_energy")]
    pm, probe, _ = physics_predictor(sw, base, free=free)
    assert pm.array is not None
    a = fit_parameters(sw, None, free, predict_many=pm, predict_array=pm.array, probe=probe)
    b = fit_parameters(sw, None, free, predict_many=pm, probe=replace(probe, predict_array=None))
    for n in a.names:
        assert a.values[n] == pytest.approx(b.values[n], rel=1e-9)
        assert a.ci_lower[n] == pytest.approx(b.ci_lower[n], rel=1e-6)
        assert a.ci_upper[n] == pytest.approx(b.ci_upper[n], rel=1e-6)
    assert a.cost == pytest.approx(b.cost, rel=1e-12)


# ------------------------------------------------------------------------------ the Jacobian
def _reference_residuals(sw, base, free, z):
    """Residuals through the reference path: one parameter set per point, ActuatorModel."""
    values = {fp.name: float(fp.from_z(v)) for fp, v in zip(free, z)}
    return residuals(ActuatorModel(apply_values(base, values)).response(sw.frequency_hz, sw.temperatures())
                     [np.searchsorted(sw.temperatures(), sw.temperature_c), np.arange(sw.frequency_hz.size)]
                     * 1e3, sw)


def _central(sw, base, free, z, h):
    cols = []
    for k in range(z.size):
        e = np.zeros_like(z)
        e[k] = h
        cols.append((_reference_residuals(sw, base, free, z + e) - _reference_residuals(sw, base, free, z - e)) / (2 * h))
    return np.column_stack(cols)


@pytest.fixture(scope="module")
def oracle(problem):
    base, truth, sw, free = problem
    point = {n: v for n, v in zip(FREE, _rows_in_box(free, 1, seed=3)[0])}
    z = np.array([float(fp.to_z(point[fp.name])) for fp in free])
    D1, D2, D4 = (_central(sw, base, free, z, h) for h in (4e-4, 2e-4, 1e-4))
    R_coarse = (4 * D2 - D1) / 3           # Richardson: O(h^4)
    R_fine = (4 * D4 - D2) / 3
    return point, R_fine, R_coarse, D2, D4


def _colerr(A, B):
    return np.linalg.norm(A - B, axis=0) / np.linalg.norm(B, axis=0)


def test_oracle_has_converged(oracle):
    _, R_fine, R_coarse, D2, D4 = oracle
    # central differences: halving h divides the error by ~4; Richardson removes it
    assert np.all(_colerr(D4, R_fine) < 0.4 * _colerr(D2, R_fine))
    assert np.max(_colerr(R_coarse, R_fine)) < 1e-8


def test_engine_jacobian_against_the_oracle(problem, oracle):
    base, _, sw, free = problem
    point, R, *_ = oracle
    pm, _, _ = physics_predictor(sw, base, free=free)
    r_ref = _reference_residuals(sw, base, free, np.array([float(fp.to_z(point[fp.name])) for fp in free]))
    errs = {}
    for step in (1e-5, 1e-6):
        r, J = residual_jacobian(sw, free, point, predict_array=pm.array, fd_step=step)
        np.testing.assert_allclose(r, r_ref, rtol=1e-9, atol=1e-9)
        errs[step] = _colerr(J, R)
    # forward differences: an O(h) error, 1e-6 relative at the engine's step, shrinking with h
    assert np.max(errs[1e-6]) < 3e-5, errs[1e-6]
    # (except where the residual is linear in z: M ∝ α0, so ∂r/∂z(α0) has no truncation error and
    # both steps agree with the oracle to rounding)
    curved = errs[1e-5] > 1e-8
    assert curved.sum() >= 6
    assert np.all(errs[1e-6][curved] < 0.3 * errs[1e-5][curved]), (errs[1e-5], errs[1e-6])
    assert np.all(errs[1e-6][~curved] < 1e-8)
    # the array path knows some columns by the chain rule (M ∝ α0: exact; laws.E.slope moves the
    # state along E's direction times (T - T_ref)); the per-set path differences every column
    assert set(pm.array.jacobian_plan) == {FREE.index("alpha0"), FREE.index("laws.E.slope")}
    _, J_sets = residual_jacobian(sw, free, point, predict_many=pm)
    assert np.max(_colerr(J_sets, R)) < 3e-5


def test_calibrated_estimate_is_stationary_for_the_reference_residuals(problem):
    base, _, sw, free = problem
    res = calibrate(sw, base, FREE, starts=3, seed=1)
    assert res.converged and not res.held
    z = np.array([float(fp.to_z(res.values[fp.name])) for fp in res.free])
    r = _reference_residuals(sw, base, res.free, z)
    J = _central(sw, base, res.free, z, 1e-3)
    step = np.linalg.lstsq(J, -r, rcond=None)[0]
    se = np.sqrt(np.diag(np.linalg.inv(J.T @ J)))
    # one Gauss-Newton step from the estimate moves it by less than 1e-4 standard errors
    # (1e-6 relative at the engine's stopping rule; the oracle's own O(h^2) error dominates here)
    assert np.max(np.abs(step / se)) < 1e-4, step / se
    # starts that joined an earlier optimum are reported as such and never chosen
    for s in res.starts:
        if s.status == -2:
            assert "stopped early" in s.message and s.cost >= res.cost
    assert res.cost == pytest.approx(min(s.cost for s in res.starts if s.status != -2), rel=1e-12)


def test_points_evaluated_together_or_apart_give_the_same_fit(problem, monkeypatch):
    # the starts advance together, each round's points sharing model calls (at most CALL_VALUES
    # predictions each): how they are grouped must not change a bit of the result, only the
    # number of calls
    from physmodel.estimation import lsq

    base, _, sw, _ = problem
    runs = []
    for per_call in (10**9, 1):          # each round's points in one call; one point per call
        monkeypatch.setattr(lsq, "CALL_VALUES", per_call)
        runs.append(calibrate(sw, base, FREE, starts=4, seed=3))
    together, apart = runs
    points = [s.nfev for s in together.starts]      # every point a Gauss-Newton or damped one here
    assert apart.n_model_calls == together.n_model_calls + sum(points) - max(points)   # a call per round
    assert apart.n_evaluations == together.n_evaluations
    for n in FREE:
        assert together.values[n] == apart.values[n]
        assert together.ci_lower[n] == apart.ci_lower[n] and together.ci_upper[n] == apart.ci_upper[n]
    assert [(s.cost, s.nfev, s.status) for s in together.starts] == [(s.cost, s.nfev, s.status) for s in apart.starts]


def test_the_kept_starts_do_not_let_a_bool_seed_through(problem):
    # the Latin-hypercube starts are kept per (free, n, seed): True == 1, but a bool seed is refused
    from physmodel.errors import ParameterError

    base, _, sw, _ = problem
    calibrate(sw, base, ["d", "alpha0"], starts=2, seed=1)
    with pytest.raises(ParameterError, match="seed must be a non-negative integer"):
        calibrate(sw, base, ["d", "alpha0"], starts=2, seed=True)


def test_a_predictor_without_independent_rows_keeps_its_calls(problem, monkeypatch):
    # grouping points differently is allowed only where each row's prediction does not depend on
    # its call (an effect model's mode count follows the lowest mode in the call): a per-set
    # predictor sees start 0's first point alone and the later starts' first points in one call,
    # however small CALL_VALUES
    from physmodel.estimation import lsq

    base, _, sw, _ = problem
    free = [default_free_parameter(base, n) for n in ("d", "alpha0", "laws.d.activation_energy")]
    pm, probe, _ = physics_predictor(sw, base, free=free)
    sizes = []

    def spy(values_list):
        sizes.append(len(values_list))
        return pm(values_list)

    monkeypatch.setattr(lsq, "CALL_VALUES", 1)
    res = fit_parameters(sw, None, free, predict_many=spy, probe=replace(probe, predict_array=None), starts=4, seed=2)
    # 1 + 3 difference sets per point: start 0's points one by one, then the later three first points together
    n0 = res.starts[0].nfev
    assert sizes[:n0] == [4] * n0 and sizes[n0] == 12 and set(sizes[n0 + 1:]) == {4}
    # the array path with a single set per point (alpha0's column is known): grouped as before too
    runs = []
    for per_call in (10**9, 1):
        monkeypatch.setattr(lsq, "CALL_VALUES", per_call)
        runs.append(calibrate(sw, base, ["alpha0"], starts=4, seed=2))
    assert runs[0].n_model_calls == runs[1].n_model_calls
    assert runs[0].values == runs[1].values


def test_starts_advancing_together_give_the_estimates_of_one_after_another(problem, monkeypatch):
    # the oracle is the engine searching the starts one after another (as it does for a predictor
    # whose rows depend on their call): the same estimates and intervals bit for bit, every start
    # either the same record or stopped in start 0's basin in both, and fewer model calls
    from physmodel.estimation import lsq

    base, _, sw, _ = problem
    for seed in (3, 4):
        together = calibrate(sw, base, FREE, starts=6, seed=seed)
        with monkeypatch.context() as m:
            m.setattr(lsq, "_regroups", lambda batch, n: False)
            apart = calibrate(sw, base, FREE, starts=6, seed=seed)
        for n in FREE:
            assert together.values[n] == apart.values[n]
            assert together.ci_lower[n] == apart.ci_lower[n] and together.ci_upper[n] == apart.ci_upper[n]
        assert together.cost == apart.cost
        for a, b in zip(together.starts, apart.starts):
            assert (a.cost, a.nfev, a.status) == (b.cost, b.nfev, b.status) or (a.status, b.status) == (-2, -2)
        assert together.n_model_calls < apart.n_model_calls


@pytest.mark.parametrize("noise_seed, starts, seed", [(301, 7, 301), (108, 10, 108), (8, 10, 108)])
def test_a_later_start_that_converges_first_does_not_replace_start_0(problem, noise_seed, starts, seed):
    # the starts advance together, so a later start can reach start 0's optimum first, at a cost
    # below start 0's by rounding: it must end in start 0's basin (joined), as when the starts run
    # one after another, and start 0 stay the best — not search on (34 points, noise seed 301) nor
    # become the best and have the others join it (noise seed 108; a reviewer's cases)
    base, truth, _, _ = problem
    sw = synthesize_sweep(ActuatorModel(truth), "M", np.logspace(-1, 2, 50), np.linspace(5.0, 75.0, 10),
                          noise=MagnitudePhaseNoise(0.1, 1.0), seed=noise_seed)
    res = calibrate(sw, base, FREE, starts=starts, seed=seed)
    recs = [(s.nfev, s.status, s.joined, s.cost) for s in res.starts]
    assert res.message.startswith("best of %d start(s) is start 0:" % starts), recs
    best = min(s.cost for s in res.starts)
    assert not [s.index for s in res.starts[1:] if s.status > 0 and s.cost <= best + 1e-6], recs
    assert all(s.joined is None or s.joined < s.index for s in res.starts), recs


@pytest.mark.parametrize("path", ["predict_many", "predict_array"])
def test_a_later_start_at_a_lower_minimum_does_not_join_a_higher_one(path):
    # a double well (a reviewer's case): minimum A at θ = 0.8, a lower one B at θ = −1 (oracle:
    # the cost by hand, ½Σr², below); start 0 (θ = 1.5) goes to A, start 1 (θ = −1.5) to B.  B is
    # below A by far more than rounding, so start 1 must not join A's basin on either predictor path
    rng = np.random.default_rng(0)
    n = 40
    e = rng.standard_normal(n)
    k, t = 0.25, np.sqrt(0.02)
    obs = ScalarObservations(np.ones(n + 2), np.ones(n + 2), tuple(f"y{i}" for i in range(n + 2)), np.zeros(n + 2),
                             "double well")

    def pa(X):
        th = X[:, 0]
        R = np.empty((len(th), n + 2))
        R[:, :n] = e
        R[:, n] = k * (th**2 - 1)
        R[:, n + 1] = t * (th + 1)
        return np.exp(R)

    pa.rows_independent = True
    cost = lambda th: 0.5 * (e @ e + (k * (th**2 - 1)) ** 2 + (t * (th + 1)) ** 2)  # noqa: E731
    kw = {"predict_array": pa} if path == "predict_array" else {
        "predict_many": lambda vs: pa(np.array([[v["th"]] for v in vs]))}
    free = [FreeParameter("th", -3.0, 3.0, "linear", 1.5)]
    r = fit_parameters(obs, None, free, starts=2, initials=[{"th": -1.5}], hold_undetermined=False, **kw)
    assert cost(-1.0) < cost(0.8) - 0.03
    assert r.values["th"] == pytest.approx(-1.0, abs=1e-6), [(s.final, s.status, s.joined) for s in r.starts]
