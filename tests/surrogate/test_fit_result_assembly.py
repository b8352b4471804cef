"""The parts of a fit result computed on first read (covariance, per-temperature errors, pole
check) against oracles the fitter does not use: a central-difference Jacobian of the model's
own frequency response, and the poles of the denominator in 50-digit arithmetic (mpmath)."""

from __future__ import annotations

import inspect

import mpmath
import numpy as np
import pytest

from surrogate import RationalFit, RationalModel, Scaling, Structure, fit_percent, relative_rms_error

# mpmath 1.4 deprecates polyroots' descending coefficient order unless ``asc`` is given;
# 1.3 has no ``asc`` and takes descending order only. Pass ascending order where the keyword
# exists (no deprecated call), descending otherwise.
_POLYROOTS_HAS_ASC = "asc" in inspect.signature(mpmath.polyroots).parameters


def _polyroots_descending(coeffs, **kw):
    """mpmath.polyroots of a polynomial given in descending powers, on mpmath 1.3 and ≥ 1.4."""
    if _POLYROOTS_HAS_ASC:
        return mpmath.polyroots(list(coeffs)[::-1], asc=True, **kw)
    return mpmath.polyroots(list(coeffs), **kw)


def _poles_mp(model: RationalModel, temperature_c):
    """Largest pole real part [rad/s] from the monic denominator in descending powers of s, in
    50-digit arithmetic (roots of the expanded polynomial, not of the sections)."""
    den = model.coefficients(temperature_c, extrapolate=True)[1]
    with mpmath.workdps(50):
        rts = _polyroots_descending([mpmath.mpf(float(c)) for c in den], maxsteps=400, extraprec=400)
        return float(max(mpmath.re(r) for r in rts))


def test_polyroots_wrapper_reads_descending_order():
    """(s + 1)(s + 2)(s - 3) = s³ - 7s - 6 in descending order: roots -2, -1, 3 exactly."""
    rts = sorted(float(mpmath.re(r)) for r in _polyroots_descending([1, 0, -7, -6]))
    assert rts == pytest.approx([-2.0, -1.0, 3.0], abs=1e-12)


@pytest.mark.parametrize("form,m,n", [("sections", 2, 4), ("sections", 3, 5), ("zpk", 2, 5)])
def test_pole_check_of_section_denominators_matches_50_digit_roots(form, m, n):
    """Includes sections with two real poles 1e4 apart (the root near zero is where a
    companion-matrix eigenvalue loses relative accuracy)."""
    rng = np.random.default_rng(11)
    st = Structure(form, m, n, 2)
    theta = rng.normal(scale=0.3, size=st.n_params)
    names = st.param_names()
    # first pole section: a1 = e^4.6 ≈ 100, a0 = e^-2.3 ≈ 0.1 → real poles ≈ -100 and -1e-3
    theta[names.index("log_a1_0:t0")], theta[names.index("log_a0_0:t0")] = 4.6, -2.3
    model = RationalModel(st, theta, Scaling(3.0, 1.0, 30.0, 15.0), (15.0, 45.0))
    temps = np.linspace(15.0, 45.0, 7)
    got = model.max_pole_real_part(temps)
    ref = np.array([_poles_mp(model, t) for t in temps])
    np.testing.assert_allclose(got, ref, rtol=1e-9)
    chk = model.stability_check(7)
    assert chk.stable and chk.max_pole_real_part_rad_s == pytest.approx(ref.max(), rel=1e-9)
    assert chk.worst_temperature_c == pytest.approx(temps[int(np.argmax(ref))])


def _noisy_fit():
    truth = RationalModel(Structure("coefficients", 1, 3, 0), [2.0, 0.5, 1.0, 1.5, 1.2], Scaling(10.0, 1.0))
    f = np.geomspace(0.2, 20.0, 50)
    rng = np.random.default_rng(5)
    h = truth.frequency_response(f) * np.exp(rng.normal(scale=0.02, size=f.size) + 1j * rng.normal(scale=0.02, size=f.size))
    sm, sp = np.full(f.size, 0.02 * 20 / np.log(10)), np.full(f.size, np.degrees(0.02))
    return f, h, sm, sp, RationalFit(1, 3).fit(f, None, h, sm, sp)


def test_deferred_covariance_equals_a_finite_difference_gauss_newton_covariance():
    """stderr / intervals / model.covariance, computed on first read, equal s²(JᵀJ)⁻¹ with J
    from central differences of the fitted model's own response (log magnitude and phase
    residuals over σ), s² the reduced χ²."""
    f, h, sm, sp, res = _noisy_fit()
    model, th = res.model, res.params
    sa, sb = sm * np.log(10) / 20, np.radians(sp)

    def resid(p):
        hm = RationalModel(model.structure, p, model.scaling).frequency_response(f)
        q = np.log(hm / h)
        return np.concatenate([q.real / sa, np.angle(hm / h) / sb])

    r0 = resid(th)
    jac = np.empty((r0.size, th.size))
    for i in range(th.size):
        e = np.zeros(th.size)
        e[i] = 1e-6 * max(1.0, abs(th[i]))
        jac[:, i] = (resid(th + e) - resid(th - e)) / (2 * e[i])
    cov = np.linalg.inv(jac.T @ jac) * (r0 @ r0) / (r0.size - th.size)
    np.testing.assert_allclose(model.covariance, cov, rtol=1e-5, atol=1e-12 * np.abs(cov).max())
    np.testing.assert_allclose(res.stderr, np.sqrt(np.diag(cov)), rtol=1e-5)
    np.testing.assert_allclose(res.ci95_high - res.ci95_low, 2 * 1.959963984540054 * np.sqrt(np.diag(cov)), rtol=1e-5)
    assert not res.covariance_rank_deficient
    assert res.weighted_rms == pytest.approx(np.sqrt(np.mean(r0 ** 2)), rel=1e-6)


def test_deferred_errors_and_pole_check_are_those_of_the_returned_model():
    f, h, _, _, res = _noisy_fit()
    hm = res.model.frequency_response(f)
    [e] = res.per_temperature
    assert e.n_lines == f.size and e.temperature_c is None
    assert e.relative_rms_error == pytest.approx(relative_rms_error(hm, h), rel=1e-12)
    assert e.fit_percent == pytest.approx(fit_percent(hm, h), rel=1e-12)
    poles = np.roots(res.model.coefficients()[1])
    assert res.stability.stable and res.stability.n_temperatures == 1
    assert res.stability.max_pole_real_part_rad_s == pytest.approx(poles.real.max(), rel=1e-9)
    # read twice: the same objects (computed once)
    assert res.per_temperature is res.per_temperature and res.stability is res.stability
    assert "stable" in res.summary()


def test_an_unread_result_pickles_and_copies_with_its_deferred_parts():
    import copy
    import pickle

    _, _, _, _, fresh = _noisy_fit()
    _, _, _, _, read = _noisy_fit()
    expect = (read.stderr, read.per_temperature, read.stability, read.covariance_rank_deficient)
    for clone in (pickle.loads(pickle.dumps(fresh)), copy.deepcopy(_noisy_fit()[-1])):
        np.testing.assert_array_equal(clone.stderr, expect[0])
        np.testing.assert_array_equal(clone.model.covariance, read.model.covariance)
        assert clone.per_temperature == expect[1] and clone.stability == expect[2]
        assert clone.covariance_rank_deficient == expect[3]
