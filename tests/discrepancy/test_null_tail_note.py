"""A quantile of the null draws with few draws beyond it is said (issue 27 review): 200-999 draws
still run, but the per-quantity gap test's quantile at α_gap/K rests on about null_draws·α_gap/K
draws (exactly ceil((null_draws − 1)·α_gap/K), ``np.quantile``'s linear interpolation), and with fewer than ``nullstats.MIN_TAIL_DRAWS`` the diagnosis says so — in its message (and so
summary.md), in ``to_dict()['null']``, in model.json's verdict reason (which every later command
reads) and, from ``ipmc diagnose``, on stderr."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from joint_cases import make_joint_case

from physmodel import IPMCParameters, load_model
from physmodel.estimation.discrepancy import diagnose
from physmodel.estimation.nullstats import MIN_TAIL_DRAWS, draws_for_tail, null_tails, thin_tail_note

FREE = ("alpha0", "d", "kappa_e", "xi", "omega_n")
PAIR = ["contact_resistance", "diffusivity_temperature"]
SEED = 902


@pytest.fixture(scope="module")
def case():
    return make_joint_case(SEED, "contact_resistance")


def _diag(case, draws):
    M, Z, truth = case
    return diagnose([M, Z], IPMCParameters.from_dict(dict(truth["library_start"])), kind="actuator", free=FREE,
                    candidates=PAIR, null_draws=draws, null_refits=0, seed=SEED)


def test_a_joint_diagnosis_on_200_draws_says_its_gap_quantile_is_thin(case, tmp_path):
    """K = 2, α = 0.05, α_gap = α/5 = 0.01: the per-quantity gap quantile (0.995) has ceil(199 × 0.005)
    = 1 draw beyond it, the pooled one (0.99) ceil(1.99) = 2, the LR threshold (0.96) ceil(7.96) = 8 — all
    under 10; 1802 draws put ceil(1801 × 0.005) = 10 beyond the 0.995 quantile (1801: 9)."""
    d = _diag(case, 200)
    tails = d.null["tails"]
    assert math.isclose(tails["per-quantity gap threshold"]["draws"], 1.0)
    assert math.isclose(tails["pooled gap threshold"]["draws"], 2.0)
    assert math.isclose(tails["LR threshold"]["draws"], 8.0)
    note = d.null["thin_tail"]
    assert note.startswith("Thin null tail") and "per-quantity gap threshold (its 0.995 quantile)" in note
    assert "null_draws ≥ 1802" in note
    assert note in d.message and note in d.summary()
    rep = json.loads(json.dumps(d.to_dict(), allow_nan=False))
    assert rep["null"]["thin_tail"] == note and note in rep["message"]
    path = d.to_model_file().save(tmp_path / "model.json")    # what later commands read: its verdict's reason
    assert note in load_model(path).verdict.reason


def test_a_joint_diagnosis_on_4000_draws_does_not(case):
    """4000 draws: ceil(3999 × 0.005) = 20 beyond the per-quantity quantile, 40 beyond the pooled, 160
    beyond the LR's."""
    d = _diag(case, 4000)
    assert min(t["draws"] for t in d.null["tails"].values()) == pytest.approx(20.0)
    assert d.null["thin_tail"] == "" and "Thin null tail" not in d.message
    assert "Thin null tail" not in d.to_model_file().verdict.reason


def test_the_threshold_is_a_relative_standard_error_of_about_a_third():
    """The realised level of a test at the empirical (1 − p) quantile of n draws: the probability
    beyond the k-th order statistic is Beta(n + 1 − k, k) (order statistics of uniforms, scipy's
    Beta, not the library's code).  At n·p = MIN_TAIL_DRAWS its relative SD is 1/sqrt(10) within
    10 %, and at the 200-draw K = 2 case (1 draw) about 100 %."""
    from scipy.stats import beta

    def rel_sd(n, p):
        k = round((n + 1) * (1 - p))                 # the order statistic at the quantile
        b = beta(n + 1 - k, k)
        return b.std() / b.mean()

    assert rel_sd(2000, 0.005) == pytest.approx(1 / math.sqrt(MIN_TAIL_DRAWS), rel=0.10)
    assert rel_sd(1000, 0.01) == pytest.approx(1 / math.sqrt(MIN_TAIL_DRAWS), rel=0.10)
    assert rel_sd(200, 0.005) > 0.65


def test_the_note_names_only_the_thin_quantiles():
    """One quantity on 400 draws: the gap quantile (ceil(3.99) = 4 draws) is thin, the LR's (16) is not;
    902 draws put ceil(9.01) = 10 beyond the gap's."""
    note = thin_tail_note(null_tails(400, 0.05, 0.01, 1), 400)
    assert "4 beyond the gap threshold" in note and "LR threshold" not in note and "null_draws ≥ 902" in note
    assert thin_tail_note(null_tails(902, 0.05, 0.01, 1), 902) == ""
    assert "9 beyond the gap threshold" in thin_tail_note(null_tails(901, 0.05, 0.01, 1), 901)
    assert thin_tail_note(null_tails(1000, 0.05, 0.01, 1), 1000) == ""


def test_the_draws_said_are_the_draws_beyond_numpys_quantile():
    """The count the note says against a direct count of draws above ``np.quantile(x, 1 − p)`` (its
    default linear interpolation, as the thresholds use) on random draws, for 200-1200 draws at every
    tail probability of α ∈ {0.01, 0.05, 0.1}, K = 1-3 — integer (n − 1)·p included.  950 draws at
    p = 0.01 leave 10 beyond (n·p would say 9.5 and call it thin), so that gap quantile is not named;
    and the draws the note asks for put 10 beyond every quantile, one fewer does not."""
    rng = np.random.default_rng(7)
    for n in range(200, 1201, 7):
        x = rng.standard_normal(n)
        for alpha in (0.01, 0.05, 0.1):
            for K in (1, 2, 3):
                for name, t in null_tails(n, alpha, alpha / 5, K).items():
                    direct = int(np.sum(x > np.quantile(x, 1 - t["tail_probability"])))
                    assert t["draws"] == direct, (n, alpha, K, name)
    x = rng.standard_normal(950)
    assert int(np.sum(x > np.quantile(x, 0.99))) == 10
    tails = null_tails(950, 0.05, 0.01, 1)
    assert tails["gap threshold"]["draws"] == 10 and thin_tail_note(tails, 950) == ""
    for p in (0.005, 0.01, 0.002, 0.01 / 3):
        n = draws_for_tail(p)
        for m, want in ((n, MIN_TAIL_DRAWS), (n - 1, MIN_TAIL_DRAWS - 1)):
            x = rng.standard_normal(m)
            assert int(np.sum(x > np.quantile(x, 1 - p))) == want, (p, m)


def test_cli_says_a_thin_tail_on_stderr(case, tmp_path, capsys):
    from scenarios.cli import main

    M, Z, truth = case
    M.to_csv(tmp_path / "M.csv")
    Z.to_csv(tmp_path / "Z.csv")
    (tmp_path / "start.json").write_text(json.dumps(dict(truth["library_start"])))
    common = ["diagnose", "--data", str(tmp_path / "M.csv"), "--data", str(tmp_path / "Z.csv"), "--set",
              str(tmp_path / "start.json"), "--candidates", ",".join(PAIR), "--null-refits", "0", "--quiet",
              *[x for f in FREE for x in ("--free", f)]]
    rc = main([*common, "--null-draws", "200", "--out", str(tmp_path / "thin")])
    err = capsys.readouterr().err
    assert rc in (0, 3) and "ipmc diagnose: Thin null tail" in err and "null_draws ≥ 1802" in err, err
    assert "Thin null tail" in json.loads((tmp_path / "thin" / "model.json").read_text())["verdict"]["reason"]
    rc = main([*common, "--null-draws", "4000", "--out", str(tmp_path / "full")])
    err = capsys.readouterr().err
    assert rc in (0, 3) and "Thin null tail" not in err, err
