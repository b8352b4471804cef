"""The diagnosis's gap test per quantity (physmodel.estimation.gap; issue 27, out-of-library row).

Oracles independent of the code: the single-quantity rule as discrepancy.py wrote it before the
gap test moved (re-typed here from its description: the pooled statistic Σ Ep², its (1 − α)
quantile, the same after projecting the effects' signatures out, and the CLOSE_FRACTION slack of
the baseline's excess); scipy's χ² quantiles for white, unprojected draws; and the binomial band of
a Monte Carlo of white-noise records for the union-bound level.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom, chi2

from physmodel.estimation.gap import GapTest, block_rows

ALPHA_GAP = 0.01          # the diagnosis's default: α = 0.05, α/5
CLOSE = 0.005             # diagnosis.CLOSE_FRACTION, as documented


def _white(rows: int, draws: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).standard_normal((rows, draws))


def _q_band(p: float, draws: int, dof: float, z: float = 4.0) -> tuple[float, float]:
    """Where the empirical p-quantile of ``draws`` χ²_dof values lies with overwhelming probability:
    the χ² quantiles at p ∓ z binomial standard errors of the count below it."""
    se = np.sqrt(p * (1 - p) / draws)
    return chi2.ppf(max(p - z * se, 1e-9), dof), chi2.ppf(min(p + z * se, 1 - 1e-9), dof)


def test_block_rows_take_each_quantitys_magnitude_and_phase_halves():
    r = block_rows([2, 3])
    assert r[0].tolist() == [0, 1, 5, 6] and r[1].tolist() == [2, 3, 4, 7, 8, 9]


def test_one_quantity_is_the_pooled_test_bit_for_bit():
    """K = 1: the thresholds and the closes rule equal the old inline code exactly (==, not ≈)."""
    rng = np.random.default_rng(3)
    Ep = rng.standard_normal((60, 500))
    sigs = {"a": rng.standard_normal((60, 2)), "b": rng.standard_normal((60, 1))}
    cost0 = 80.0
    g = GapTest.from_null(Ep, ALPHA_GAP, [cost0], sigs, ("M",))
    cost2_null = np.sum(Ep * Ep, axis=0)
    thr0 = float(np.quantile(cost2_null, 1 - ALPHA_GAP))
    assert g.thr0.tolist() == [thr0] and g.K == 1 and g.rows is None
    for effs in (["a"], ["b"], ["a", "b"]):
        Q, R = np.linalg.qr(np.hstack([sigs[c] for c in effs]))
        Q = Q[:, np.abs(np.diag(R)) > 1e-10 * max(1.0, np.abs(np.diag(R)).max())]
        thr = float(np.quantile(cost2_null - np.sum((Q.T @ Ep) ** 2, axis=0), 1 - ALPHA_GAP))
        assert g.thresholds(effs).tolist() == [thr]
        for cost in np.linspace(0.3 * thr, 1.2 * thr, 41):
            old = 2 * cost <= thr or 2 * cost - thr <= CLOSE * max(2 * cost0 - thr0, 0.0)
            assert g.closes([cost], effs) is bool(old)
            assert g.strict([cost], effs) is bool(2 * cost <= thr)
    assert g.significant0 is bool(2 * cost0 > thr0)
    assert g.compare([cost0]) == f"2·cost {2 * cost0:.4g} > {thr0:.4g}"
    # the pooled test is the one block: not run a second time, not said, not reported
    assert g.pooled_threshold() == thr0 and g.threshold_text() == f"{thr0:.4g}"
    assert g.open_in([cost0]) == (["M"] if 2 * cost0 - thr0 > CLOSE * max(2 * cost0 - thr0, 0.0) else [])
    assert g.pooled_row([{"cost_before": cost0, "cost_after": cost0}]) is None and "pooled" not in g.describe()


def test_per_block_thresholds_are_the_chi2_quantiles_at_the_bonferroni_level():
    """White, unprojected draws: each block's threshold is χ²_{2n_k} at 1 − α_gap/K (scipy)."""
    sizes, draws = (50, 500), 20000
    Ep = _white(2 * sum(sizes), draws, 11)
    g = GapTest.from_null(Ep, ALPHA_GAP, [0.0, 0.0], None, ("M", "Z"), sizes)
    assert g.level == 1 - ALPHA_GAP / 2
    for k, n in enumerate(sizes):
        lo, hi = _q_band(1 - ALPHA_GAP / 2, draws, 2 * n)
        assert lo <= g.thr0[k] <= hi, (k, g.thr0[k], chi2.ppf(1 - ALPHA_GAP / 2, 2 * n), lo, hi)
    # the pooled test: χ²_{2N} at 1 − α_gap (the whole α_gap, not shared out)
    lo, hi = _q_band(1 - ALPHA_GAP, draws, 2 * sum(sizes))
    assert lo <= g.pooled_threshold() <= hi, (g.pooled_threshold(), chi2.ppf(1 - ALPHA_GAP, 2 * sum(sizes)))


def test_a_gap_in_one_quantity_only_is_found_per_block_where_the_pooled_test_misses_it():
    """M (100 rows) carries a gap at its χ² 1 − 1e-4 point, Z (1000 rows) sits at its mean: the
    pooled statistic is inside its own χ² quantile (scipy), the per-quantity test rejects in M."""
    sizes = (50, 500)
    Ep = _white(2 * sum(sizes), 20000, 12)
    two_m, two_z = chi2.ppf(1 - 1e-4, 100), 1000.0
    assert two_m + two_z < chi2.ppf(1 - ALPHA_GAP, 1100)              # the pooled test would not see it
    g = GapTest.from_null(Ep, ALPHA_GAP, [two_m / 2, two_z / 2], None, ("M", "Z"), sizes)
    assert g.significant0
    assert g.open_in(g.cost0) == ["M"]
    assert "M: 2·cost" in g.compare(g.cost0) and "Z: 2·cost" in g.compare(g.cost0)
    # closing needs every block: the pooled sum within the pooled quantile is not enough
    thr = g.thresholds()
    assert not g.closes([thr[0] / 2 + 1.0, 0.25 * thr[1]])
    # the slack is CLOSE_FRACTION of the block's own baseline excess (M's), none where there was none (Z)
    ex = 2 * g.cost0[0] - thr[0]
    assert g.excess0[1] == 0.0 and g.excess0[0] == pytest.approx(ex)
    assert g.closes([(thr[0] + 0.9 * CLOSE * ex) / 2, 0.5 * thr[1] / 2])
    assert not g.closes([(thr[0] + 1.1 * CLOSE * ex) / 2, 0.5 * thr[1] / 2])
    assert not g.closes([0.5 * thr[0] / 2, (thr[1] + 1e-6) / 2])
    assert g.strict([0.5 * thr[0] / 2, 0.5 * thr[1] / 2])
    rows = g.annotate([{"cost_before": g.cost0[0], "cost_after": thr[0] / 2 + 5.0},
                       {"cost_before": g.cost0[1], "cost_after": g.cost0[1]}])
    assert [r["gap_before"] for r in rows] == [True, False] and [r["gap_left"] for r in rows] == [True, False]


def test_a_model_inside_each_quantitys_threshold_but_beyond_the_pooled_one_does_not_close():
    """Issue 27: each block's 2·cost at its χ²_100 0.985 point, below the band of its own threshold
    at 1 − α_gap/2; their sum above the band of the pooled χ²_200 quantile at 1 − α_gap (scipy, white
    unprojected draws) by more than the slack a baseline pooled excess of at most 500 − that band's
    lower end allows.  Closed in every quantity, open pooled: the gap is not closed, and the
    report says which test left it open."""
    from physmodel.estimation.joint import per_quantity_sentence

    sizes, draws = (50, 50), 20000
    g = GapTest.from_null(_white(200, draws, 41), ALPHA_GAP, [200.0, 50.0], None, ("M", "Z"), sizes)
    two_k = chi2.ppf(0.985, 100)
    assert two_k < _q_band(1 - ALPHA_GAP / 2, draws, 100)[0]            # within each block's threshold
    p_lo, p_hi = _q_band(1 - ALPHA_GAP, draws, 200)
    assert 2 * two_k - p_hi > CLOSE * (500.0 - p_lo)                    # beyond the pooled one and its slack
    costs = [two_k / 2, two_k / 2]
    assert g.closes_blocks(costs).tolist() == [True, True]
    assert not g.closes(costs) and not g.strict(costs)
    assert g.open_in(costs) == ["pooled over M and Z"]
    assert "pooled over M and Z at 0.01: 2·cost" in g.compare(costs) and " > " in g.compare(costs).split(";")[-1]
    # the baseline's significance stays per quantity (M's 400 is far above its threshold)
    assert g.significant0 and g.significant(costs) is False
    rows = g.annotate([{"quantity": q, "lines": 50, "noise": "declared", "sigma_db_median": 0.1, "sigma_deg_median": 1.0,
                        "cost_before": c0, "cost_after": two_k / 2, "expected_after": 49.0, "misfit": False}
                       for q, c0 in zip("MZ", g.cost0)])
    pooled = g.pooled_row(rows)
    assert pooled["gap_left"] and pooled["gap_before"] and not any(r["gap_left"] for r in rows)
    assert pooled["two_cost_after"] == pytest.approx(2 * two_k)
    said = per_quantity_sentence(rows, pooled)
    assert "leaves the gap open pooled over M and Z (2·cost" in said and "each quantity alone closes it" in said
    assert "open in M" not in said and "open in Z" not in said
    # the same residual, one quantity's worth less: within the pooled threshold, it closes
    assert g.closes([two_k / 2, (g.pooled_threshold() - two_k - 1.0) / 2])
    # the pooled slack: CLOSE_FRACTION of the baseline's pooled excess, no more
    ex = 2 * 250.0 - g.pooled_threshold()
    assert g.pooled_excess0 == pytest.approx(ex)
    for f, ok in ((0.9, True), (1.1, False)):
        two = g.pooled_threshold() + f * CLOSE * ex
        assert g.closes_blocks([two / 4, two / 4]).all() and g.closes([two / 4, two / 4]) is ok


def test_a_correct_model_fails_to_close_at_most_twice_alpha_gap():
    """The rule's price on white-noise records (a correct model's residual; fresh draws, not the
    null's; no baseline excess, so no slack): some test of the gap — a block at α_gap/2 or the pooled
    one at α_gap — rejects with a probability within [α_gap, 2·α_gap] (the larger of the two
    families' own rates, their union bound), the count within its binomial band."""
    sizes, draws, m = (155, 155), 8000, 40000
    g = GapTest.from_null(_white(2 * sum(sizes), draws, 51), ALPHA_GAP, [0.0, 0.0], None, ("M", "Z"), sizes)
    r = _white(2 * sum(sizes), m, 52)
    costs = np.vstack([0.5 * np.sum(r[i] ** 2, axis=0) for i in block_rows(sizes)])
    k = sum(not g.closes(costs[:, j]) for j in range(m))
    se = np.sqrt(ALPHA_GAP * (1 - ALPHA_GAP) / draws)           # the thresholds' own Monte-Carlo error
    assert binom.ppf(1e-4, m, ALPHA_GAP - 4 * se) <= k <= binom.ppf(1 - 1e-4, m, 2 * ALPHA_GAP + 4 * se), (k, m)


def test_the_union_bound_holds_the_family_wise_level_on_white_noise():
    """Records of white noise (fresh draws, not the null's): the rule 'some block above its own
    threshold' rejects at its exact rate for independent blocks, 1 − Π_k F_χ²(thr_k; 2n_k)
    (scipy), within its binomial band — and that rate is α_gap within the thresholds' own
    Monte-Carlo error (each block's tail 1 − F at α_gap/K ± 4 binomial SE of the null draws)."""
    sizes, draws, m = (155, 155), 8000, 40000
    g = GapTest.from_null(_white(2 * sum(sizes), draws, 21), ALPHA_GAP, [0.0, 0.0], None, ("M", "Z"), sizes)
    tails = np.array([chi2.sf(t, 2 * n) for t, n in zip(g.thr0, sizes)])
    se = np.sqrt(ALPHA_GAP / 2 * (1 - ALPHA_GAP / 2) / draws)
    assert np.all(np.abs(tails - ALPHA_GAP / 2) <= 4 * se), tails
    p_exact = 1 - np.prod(1 - tails)
    assert p_exact <= ALPHA_GAP + 2 * 4 * se
    r = _white(2 * sum(sizes), m, 22)
    costs = np.vstack([0.5 * np.sum(r[i] ** 2, axis=0) for i in block_rows(sizes)])
    k = int(np.sum(g.significant(costs)))
    assert binom.ppf(1e-4, m, p_exact) <= k <= binom.ppf(1 - 1e-4, m, p_exact), (k, m * p_exact)


def test_blocks_add_up_to_the_pooled_statistic_with_effects_projected_out():
    """An invariant: the blocks' null 2·cost sum to the pooled one (one block of every row)."""
    rng = np.random.default_rng(4)
    Ep = rng.standard_normal((2 * 30, 300))
    sigs = {"a": rng.standard_normal((60, 2))}
    two = GapTest.from_null(Ep, ALPHA_GAP, [0.0, 0.0], sigs, ("M", "Z"), (10, 20))
    one = GapTest.from_null(Ep, ALPHA_GAP, [0.0], sigs, ("M+Z",))
    for effs in ((), ("a",)):
        np.testing.assert_allclose(two.null_costs(effs).sum(axis=0), one.null_costs(effs)[0], rtol=1e-10)


def test_mismatched_quantity_names_are_refused():
    with pytest.raises(ValueError, match="quantity names"):
        GapTest.from_null(np.zeros((6, 10)), ALPHA_GAP, [0.0], None, ("M",), (1, 2))


def test_a_weak_effect_in_M_alone_is_unexplained_jointly_and_the_report_says_where():
    """Development seed 48204, a gain ripple (out of the library) on M only (λ 40 after the
    generator's baseline refit): the pooled gap test over M and Z had ended ``none`` (2·cost 687 over
    620 rows); M's own block is above its threshold, Z's is not (independent generator, no physmodel
    physics)."""
    from joint_cases import make_joint_case

    from physmodel import IPMCParameters
    from physmodel.estimation.discrepancy import diagnose

    M, Z, truth = make_joint_case(48204, "gain_ripple")
    base = IPMCParameters.from_dict(dict(truth["library_start"]))
    d = diagnose([M, Z], base, kind="actuator", free=("alpha0", "d", "kappa_e", "xi", "omega_n"), seed=48204)
    rows = {r["quantity"]: r for r in d.per_quantity}
    assert d.verdict == "unexplained", d.message
    assert rows["M"]["gap_before"] and rows["M"]["gap_left"] and not rows["Z"]["gap_before"], rows
    assert 2 * rows["M"]["cost_before"] > rows["M"]["gap_threshold_before_2cost"]
    assert "leaves the gap open in M" in d.message and "open in M (" in d.message and "Z (2·cost" not in d.message
    assert np.isnan(d.gap_threshold) and set(d.null["gap_test"]["thresholds_2cost"]) == {"M", "Z"}
    assert d.null["gap_test"]["level_per_block"] == 1 - d.null["alpha_gap"] / 2
    assert "gap threshold on 2·cost" in d.summary() and "gap left" in d.summary()


def test_the_residual_sentence_names_the_quantity_it_is_about():
    from types import SimpleNamespace

    sizes = (50, 50)
    g = GapTest.from_null(_white(200, 4000, 31), ALPHA_GAP, [200.0, 40.0], None, ("M", "Z"), sizes)
    thr = g.thresholds()
    res = SimpleNamespace(names=["a", "b"], metadata={}, expected_cost=99.0)
    # M above its threshold by far (significant), Z within: one sentence, about M
    s = g.residual_sentence(res, [thr[0], 0.4 * thr[1]])
    assert "The residual misfit in M is significant" in s and "Z" not in s
    # Z above its threshold where the baseline had no gap there: said so, no share of a zero excess
    s = g.residual_sentence(res, [0.4 * thr[0], 0.5 * thr[1] + 1.0])
    assert "in Z" in s and "no significant gap there" in s and " M " not in s
    assert g.residual_sentence(res, [0.4 * thr[0], 0.4 * thr[1]]) == ""
