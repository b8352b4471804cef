"""The engine on scalar observations (ScalarObservations): residuals ln|y_model/y|/σ_ln.

Oracles, independent of the engine: a model whose logarithm is linear in the fitted coordinates
(y = A·exp(−E/(R T)), A on a log scale, E linear), for which weighted least squares has a closed
form (a weighted linear regression solved by numpy's lstsq) with the exact covariance (XᵀWX)⁻¹;
the χ² of that closed-form optimum; a parameter the model does not use (zero sensitivity)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from physmodel.errors import IPMCError
from physmodel.estimation.lsq import Z95, fit_parameters
from physmodel.estimation.observations import ScalarObservations
from physmodel.estimation.records import FreeParameter

R = 8.314462618
T = np.array([283.15, 293.15, 303.15, 313.15, 323.15, 333.15, 343.15])
SIGMA = np.array([0.02, 0.03, 0.02, 0.05, 0.02, 0.04, 0.03])
FREE = [FreeParameter("A", 1e3, 1e9, "log", 1e5), FreeParameter("E", 0.0, 80e3, "linear", 20e3)]


def _model(values_list):
    return np.array([[v["A"] * math.exp(-v["E"] / (R * t)) for t in T] for v in values_list])


def _data(seed):
    rng = np.random.default_rng(seed)
    y = 3e6 * np.exp(-35e3 / (R * T)) * np.exp(SIGMA * rng.standard_normal(T.size))
    return ScalarObservations(y, SIGMA, tuple(f"y({t:g} K)" for t in T), T - 273.15, "synthetic Arrhenius")


def _closed_form(obs):
    X = np.column_stack([np.ones(T.size), -1.0 / (R * T)]) / SIGMA[:, None]
    b = np.log(obs.values) / SIGMA
    (lnA, E), *_ = np.linalg.lstsq(X, b, rcond=None)
    cov = np.linalg.inv(X.T @ X)
    r = X @ [lnA, E] - b
    return lnA, E, cov, float(r @ r)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_log_linear_model_matches_the_closed_form_weighted_regression(seed):
    obs = _data(seed)
    res = fit_parameters(obs, None, FREE, starts=2, seed=seed, predict_many=_model)
    lnA, E, cov, chi2 = _closed_form(obs)
    assert res.converged and res.held == []
    assert res.values["A"] == pytest.approx(math.exp(lnA), rel=1e-6)
    assert res.values["E"] == pytest.approx(E, rel=1e-6, abs=1e-3)
    # intervals: E ± 1.96 se, A = exp(lnA ± 1.96 se) (log scale, asymmetric)
    se_lnA, se_E = math.sqrt(cov[0, 0]), math.sqrt(cov[1, 1])
    assert res.ci_lower["E"] == pytest.approx(E - Z95 * se_E, rel=1e-5)
    assert res.ci_upper["E"] == pytest.approx(E + Z95 * se_E, rel=1e-5)
    assert res.ci_lower["A"] == pytest.approx(math.exp(lnA - Z95 * se_lnA), rel=1e-5)
    assert res.ci_upper["A"] == pytest.approx(math.exp(lnA + Z95 * se_lnA), rel=1e-5)
    assert res.correlation[0, 1] == pytest.approx(cov[0, 1] / (se_lnA * se_E), rel=1e-5)
    # χ² over N residuals (not 2N), on N − 2 degrees of freedom
    g = res.goodness_of_fit
    assert g.dof == T.size - 2 and g.chi2 == pytest.approx(chi2, rel=1e-6)
    assert res.expected_cost == pytest.approx((T.size - 2) / 2)
    assert res.n_lines == T.size and res.temperatures_c == pytest.approx((T - 273.15).tolist())
    assert all(math.isnan(v.sensitivity_peak_hz) for v in res.identifiability.values())


def test_a_parameter_the_model_ignores_is_held_with_zero_sensitivity():
    obs = _data(4)
    free = FREE + [FreeParameter("unused", -1.0, 1.0, "linear", 0.25)]
    for hold in (True, "insensitive"):
        res = fit_parameters(obs, None, free, starts=1, predict_many=_model, hold_undetermined=hold)
        assert res.held == ["unused"] and res.values["unused"] == 0.25 and math.isnan(res.ci_lower["unused"])
        assert "zero sensitivity" in res.identifiability["unused"].reason
        lnA, E, _, _ = _closed_form(obs)
        assert res.values["E"] == pytest.approx(E, rel=1e-6)
    with pytest.raises(IPMCError, match="hold_undetermined"):
        fit_parameters(obs, None, free, predict_many=_model, hold_undetermined="some")


def test_insensitive_holding_keeps_an_undetermined_parameter_fitted():
    """Two observations at nearly one temperature cannot separate A from E: with
    hold_undetermined=True the worst is held; with "insensitive" both keep their fit and wide intervals."""
    obs = ScalarObservations([1.0, 1.01, 0.99], [0.5, 0.5, 0.5], ("a", "b", "c"))
    T3 = np.array([300.0, 300.5, 301.0])

    def model(vl):
        return np.array([[v["A"] * math.exp(-v["E"] / (R * t)) for t in T3] for v in vl])

    held = fit_parameters(obs, None, FREE, predict_many=model)
    kept = fit_parameters(obs, None, FREE, predict_many=model, hold_undetermined="insensitive")
    assert held.held and not kept.held
    assert not all(kept.identifiability[n].identifiable for n in ("A", "E"))
    assert all(math.isfinite(kept.ci_lower[n]) for n in ("A", "E"))


def test_bad_observations_and_bad_model_values_are_named():
    with pytest.raises(IPMCError, match="sigma_ln.*b"):
        ScalarObservations([1.0, 2.0], [0.1, 0.0], ("a", "b"))
    with pytest.raises(IPMCError, match="finite and nonzero.*'a'"):
        ScalarObservations([0.0, 2.0], [0.1, 0.1], ("a", "b"))
    with pytest.raises(IPMCError, match="2 values need as many"):
        ScalarObservations([1.0, 2.0], [0.1], ("a", "b"))
    with pytest.raises(IPMCError, match="non-empty 1-D"):
        ScalarObservations([], [])
    obs = ScalarObservations([1.0, 2.0, 3.0], [0.1, 0.1, 0.1], ("a", "b", "c"))
    with pytest.raises(IPMCError, match="zero or not finite.*'b'"):
        fit_parameters(obs, None, FREE, predict_many=lambda vl: np.array([[1.0, 0.0, 3.0]] * len(vl)))
    with pytest.raises(IPMCError, match="3 scalar observations cannot determine 3"):
        fit_parameters(obs, None, FREE + [FreeParameter("x", 0.0, 1.0)], predict_many=_model)
    with pytest.raises(IPMCError, match="FrequencySweep or ScalarObservations"):
        fit_parameters({"y": 1}, None, FREE, predict_many=_model)
