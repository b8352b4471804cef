"""Scheduled fits: synthetic recovery within confidence intervals, stability, baselines."""

import numpy as np
import pytest
from surrogate_fixtures import FIT_TEMPS, TRUE_SCALING, TRUE_THETA, noisy_sweep

from surrogate import ConvergenceError, RationalModel, Scaling, ScheduledFit, Structure, relative_rms_error

SCALES = dict(omega_ref_rad_s=TRUE_SCALING.omega_ref_rad_s, gain_ref=TRUE_SCALING.gain_ref,
              temperature_center_c=TRUE_SCALING.temperature_center_c,
              temperature_scale_c=TRUE_SCALING.temperature_scale_c)


@pytest.fixture(scope="module")
def joint_zpk(synthetic_sweep):
    f, t, h, sm, sp = synthetic_sweep
    return ScheduledFit("zpk", 2, 3, 2, **SCALES).fit(f, t, h, sm, sp)


def test_true_model_has_a_real_to_complex_zero_transition(true_model):
    z_cold, z_hot = true_model.zeros(19.0), true_model.zeros(55.0)
    assert np.all(np.abs(z_cold.imag) < 1e-12) and np.all(np.abs(z_hot.imag) > 1.0)
    assert np.all(z_cold.real > 0) and np.all(z_hot.real > 0)  # non-minimum phase throughout


def test_synthetic_scheduled_recovery_within_confidence_intervals(joint_zpk, true_model):
    # pooled over five noise draws (seed 3, the module's fit, and 4-7): 18 coefficients of one
    # draw are too few for a coverage claim (one draw, seed 3, has 4 of 18 outside their 95 %
    # intervals; P ≈ 1-2 % for honest intervals)
    fits = [joint_zpk] + [
        ScheduledFit("zpk", 2, 3, 2, **SCALES).fit(*noisy_sweep(true_model, FIT_TEMPS, np.geomspace(0.1, 30, 40),
                                                                seed=seed))
        for seed in (4, 5, 6, 7)]
    z, inside = [], []
    for res in fits:
        assert res.converged and res.method == "joint"
        assert np.all(res.ci95_low < res.ci95_high)
        z.append((res.params - TRUE_THETA) / res.stderr)
        inside.append((TRUE_THETA >= res.ci95_low) & (TRUE_THETA <= res.ci95_high))
        # correct uncertainties: weighted residual RMS close to 1
        assert 0.85 < res.weighted_rms < 1.15
    z, inside = np.concatenate(z), np.concatenate(inside)
    # every coefficient within 3.5 standard errors …
    assert np.max(np.abs(z)) < 3.5, z
    # … and the intervals are honest, neither inflated nor too narrow
    assert 0.5 < np.sqrt(np.mean(z ** 2)) < 1.6, z
    assert inside.mean() >= 0.8


def test_joint_fit_reproduces_the_response_at_unseen_temperatures(joint_zpk, true_model):
    f = np.geomspace(0.1, 30, 50)
    for t in (22.0, 35.0, 46.0):
        err = relative_rms_error(joint_zpk.model.frequency_response(f, t), true_model.frequency_response(f, t))
        assert err < 0.01, (t, err)


def test_zpk_schedule_is_stable_on_a_dense_grid(joint_zpk):
    st = joint_zpk.model.stability_check(2001)
    assert st.stable and st.n_temperatures == 2001
    grid = np.linspace(19.0, 55.0, 301)
    assert max(np.max(joint_zpk.model.poles(t).real) for t in grid) < 0


def test_two_stage_baseline_is_returned_and_available(joint_zpk, synthetic_sweep):
    assert isinstance(joint_zpk.two_stage, RationalModel)
    assert sorted(joint_zpk.per_temperature_models) == FIT_TEMPS
    f, t, h, sm, sp = synthetic_sweep
    two = ScheduledFit("zpk", 2, 3, 2, method="two-stage", **SCALES).fit(f, t, h, sm, sp)
    assert two.method == "two-stage" and two.stderr is None
    np.testing.assert_allclose(two.params, joint_zpk.two_stage.params, rtol=1e-6, atol=1e-9)
    # the joint fit minimises the same objective the two-stage result is scored on
    assert joint_zpk.cost <= two.cost + 1e-12


def test_coefficients_form_is_stable_on_dense_grid_and_matches_truth(synthetic_sweep, true_model):
    f, t, h, sm, sp = synthetic_sweep
    res = ScheduledFit("coefficients", 2, 3, 3).fit(f, t, h, sm, sp)
    assert res.converged
    grid = np.linspace(19.0, 55.0, 1001)
    worst = max(np.max(np.roots(res.model.coefficients(T)[1]).real) for T in grid)
    assert worst < 0 and res.stability.stable
    fq = np.geomspace(0.1, 30, 50)
    err = relative_rms_error(res.model.frequency_response(fq, 40.0), true_model.frequency_response(fq, 40.0))
    assert err < 0.01


def test_levy_two_stage_is_the_papers_baseline(synthetic_sweep):
    f, t, h, sm, sp = synthetic_sweep
    res = ScheduledFit("coefficients", 2, 3, 2, per_temperature="levy").fit(f, t, h, sm, sp)
    assert all(e["start"] == "levy" for e in res.history if e["stage"].startswith("per-T"))
    assert res.converged and res.cost <= ScheduledFit(
        "coefficients", 2, 3, 2, per_temperature="levy", method="two-stage").fit(f, t, h, sm, sp).cost


def test_joint_non_convergence_is_reported(synthetic_sweep):
    f, t, h, sm, sp = synthetic_sweep
    fit = ScheduledFit("zpk", 2, 3, 2, max_iter=1)
    with pytest.raises(ConvergenceError) as info:
        fit.fit(f, t, h, sm, sp)
    assert not info.value.result.converged
    assert "Maximum_Iterations_Exceeded" in str(info.value)
    res = ScheduledFit("zpk", 2, 3, 2, max_iter=1, raise_on_failure=False).fit(f, t, h, sm, sp)
    assert not res.converged and res.status == "Maximum_Iterations_Exceeded"
    assert "NOT CONVERGED" in res.summary()


def test_scheduled_fit_rejects_too_few_temperatures(synthetic_sweep):
    f, t, h, sm, sp = synthetic_sweep
    keep = np.isin(t, [19.0, 25.0])
    with pytest.raises(ValueError, match="degree=2 needs at least 3 distinct temperatures"):
        ScheduledFit("zpk", 2, 3, 2).fit(f[keep], t[keep], h[keep])


def test_structure_conversion_preserves_the_response():
    rng = np.random.default_rng(0)
    from surrogate._convert import convert
    from surrogate._structure import response

    w = np.geomspace(0.05, 20, 30)
    for _ in range(20):
        st = Structure("sections", 3, 4, 0)
        theta = np.concatenate([rng.normal(size=4), rng.normal(scale=0.5, size=4)])
        ref = response(st, theta, w, 0.0)
        for form in ("coefficients", "zpk"):
            th2 = convert(st, theta, form)
            np.testing.assert_allclose(response(st.with_form(form), th2, w, 0.0), ref, rtol=1e-8)


@pytest.mark.parametrize("num, zeros", [
    ([0.6, -0.5, 0.0, 0.0], [1.2]),                       # two zeros at infinity: β2 = β = 0
    ([0.0, 0.6, -0.5, 0.2], [0.0, 1.25 + 1.19896j, 1.25 - 1.19896j]),   # a zero at the origin
    ([-0.3, 0.1, 0.4, -0.2], None),                       # three finite zeros, one in the RHP
])
def test_unit_zero_sections_carry_zeros_at_infinity_and_near_the_origin(num, zeros):
    """The 'zpk' numerator k·(1 + β1 s̃ + β2 s̃²)(1 + β s̃): a zero at infinity is β = 0, a finite
    point; a zero at the origin has no β and is moved to |s̃| = 1e-12 (the response is kept to
    ~1e-12·|s̃| relative).  Oracle: numpy's polyval of the numerator written here."""
    from surrogate._convert import convert
    from surrogate._structure import response

    w = np.geomspace(0.05, 20, 30)
    st = Structure("coefficients", 3, 4, 0)
    den = [2.0, 1.5, 3.0, 0.8]
    theta = np.array(num + den)
    s = 1j * w
    ref = np.polyval(num[::-1], s) / np.polyval((den + [1.0])[::-1], s)
    th2 = convert(st, theta, "zpk")
    np.testing.assert_allclose(response(st.with_form("zpk"), th2, w, 0.0), ref, rtol=1e-9)
    assert th2[0] == pytest.approx(num[0] if num[0] else -1e-12 * num[1])      # k: the numerator at 0
    if zeros is not None:        # the finite zeros (a zero at infinity is not listed)
        z = RationalModel(st.with_form("zpk"), th2, Scaling(1.0, 1.0)).zeros()
        np.testing.assert_allclose(np.sort_complex(z), np.sort_complex(zeros), atol=1e-4)


def test_hurwitz_constraints_keep_the_coefficients_form_stable():
    # truth: a resonance whose damping coefficient a1(τ) = 0.1 − 0.2τ turns negative above mid-range
    st = Structure("coefficients", 0, 2, 1)
    theta = np.array([[1.0, 0.0], [1.0, 0.0], [0.1, -0.2]]).ravel()  # b0, a0, a1
    truth = RationalModel(st, theta, TRUE_SCALING, (19.0, 55.0))
    assert not truth.stability_check().stable
    temps = [19.0, 28.0, 37.0, 46.0, 55.0]
    f, t, h, sm, sp = noisy_sweep(truth, temps, np.geomspace(0.5, 10, 30), mag_db=0.01, ph_deg=0.06)
    free = ScheduledFit("coefficients", 0, 2, 1, enforce_stability=False, **SCALES).fit(f, t, h, sm, sp)
    np.testing.assert_allclose(free.params, theta, atol=5e-3)
    assert not free.stability.stable
    held = ScheduledFit("coefficients", 0, 2, 1, enforce_stability=True, **SCALES).fit(f, t, h, sm, sp)
    assert any(e["stage"].startswith("joint (Hurwitz constraints") for e in held.history)
    assert held.stability.stable and held.converged
    grid = np.linspace(19.0, 55.0, 1001)
    assert max(np.max(np.roots(held.model.coefficients(T)[1]).real) for T in grid) < 0
    # the constraints hold the shifted denominator D(s − σ) Hurwitz: Re p ≤ −σ at the 41
    # constrained temperatures (σ = stability_margin·ω_ref), checked with numpy's roots
    margin = held.model.info["settings"]["stability_margin"] * held.model.scaling.omega_ref_rad_s
    re = [np.max(np.roots(held.model.coefficients(T)[1]).real) for T in np.linspace(19.0, 55.0, 41)]
    assert max(re) <= -margin * (1 - 1e-6)
    assert max(re) == pytest.approx(-margin, rel=0.1)       # active (the truth is unstable)


@pytest.mark.parametrize("max_iter", [1, 2, 3])
def test_coefficients_form_is_stable_whatever_the_solvers_exit_status(max_iter):
    """The unstable-truth sweep above with an iteration cap below the resume threshold: every
    solve ends unconverged, and unconverged answers near the unstable truth used to be returned
    as they were (a pole at +0.9 rad/s, flagged only as out of iterations).  An answer of the
    coefficients form with enforce_stability is stable on a dense grid (numpy's roots of the
    returned denominators), or its status says that no stable solve was found."""
    st = Structure("coefficients", 0, 2, 1)
    truth = RationalModel(st, np.array([1.0, 0.0, 1.0, 0.0, 0.1, -0.2]), TRUE_SCALING, (19.0, 55.0))
    f, t, h, sm, sp = noisy_sweep(truth, [19.0, 28.0, 37.0, 46.0, 55.0], np.geomspace(0.5, 10, 30),
                                  mag_db=0.01, ph_deg=0.06)
    res = ScheduledFit("coefficients", 0, 2, 1, max_iter=max_iter, raise_on_failure=False,
                       **SCALES).fit(f, t, h, sm, sp)
    assert not res.converged
    worst = max(np.max(np.roots(res.model.coefficients(T)[1]).real) for T in np.linspace(19.0, 55.0, 1001))
    assert worst < 0 or res.status.startswith("Unstable_Solution"), (res.status, worst)
    assert res.stability.stable == (worst < 0)
