"""The discrepancy workflow on blind synthetic cases (known truth hidden under sealed seeds), its null
calibration (the χ̄² boundary mixture of discrepancy.md §3), the report and the CLI."""

import argparse
import json

import numpy as np
import pytest

from physmodel import IPMCError, ParameterError, get_parameter_set
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from physmodel.effects.library import OUT_OF_LIBRARY, EffectModel
from physmodel.estimation.discrepancy import VERDICTS, constrained_lr, diagnose, gap_shrink

P = get_parameter_set("seed002_table3")
F = np.logspace(-1, 1.7, 30)
T = [20.0, 40.0, 60.0]
FREE = ("alpha0", "d", "xi", "omega_n")
#: The generator's sealed entropy: sizes, noise and noise seeds come from here, never from diagnose.
SEALED = 0x5EA1ED


def _hidden(case: int, effects_fn):
    rng = np.random.default_rng(np.random.SeedSequence(SEALED, spawn_key=(case,)))
    noise = MagnitudePhaseNoise(float(rng.uniform(0.15, 0.3)), float(rng.uniform(0.8, 1.5)))
    effects = effects_fn(rng)
    data = synthesize_sweep(EffectModel(P, "actuator", effects), "M", F, T, noise,
                            seed=int(rng.integers(2**31)))
    data = type(data)(**{**data.__dict__, "metadata": {}})       # the workflow never sees the label
    return data, effects


#: The five blind cases: label -> the hidden effects drawn from the case's sealed generator.
BLIND_CASES = {
    "none": lambda r: {},
    "time_delay": lambda r: {"time_delay": {"delay": r.uniform(1.5e-3, 4e-3)}},
    "fractional_transport": lambda r: {"fractional_transport": {"beta": r.uniform(0.85, 0.92)}},
    "fixture_resonance": lambda r: {"fixture_resonance": {"frequency_hz": r.uniform(1.0, 20.0),
                                                          "depth": r.uniform(0.5, 0.8), "damping": 0.05}},
    "two": lambda r: {"time_delay": {"delay": r.uniform(1.5e-3, 3e-3)},
                      "fractional_transport": {"beta": r.uniform(0.85, 0.9)}},
}


def _blind_diagnosis(label: str):
    """One blind case's full diagnosis (default null calibration), warnings as errors as in the suite
    (it may run in a worker process, outside pytest's filter)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        data, _ = _hidden(list(BLIND_CASES).index(label), BLIND_CASES[label])
        return label, diagnose(data, P, kind="actuator", free=FREE, seed=0)


#: Five full diagnoses with null calibration (about 100 s of CPU): the tests that use them, and the
#: other end-to-end diagnoses, are in the slow tier; the fast tier keeps the null mixture, the bad-input,
#: the implausible-baseline and the CLI tests.  The five are independent and deterministic (sealed
#: seeds, seed=0), so they run in up to two worker processes when the machine gives this process two
#: cores (CI's runners): the same results, about half the wall time.
@pytest.fixture(scope="module")
def blind():
    import multiprocessing
    import os

    workers = min(2, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)
    if workers < 2:
        return dict(map(_blind_diagnosis, BLIND_CASES))
    threads = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
    saved = {k: os.environ.get(k) for k in threads}
    os.environ.update({k: "1" for k in threads})      # two workers x one BLAS thread on two cores
    try:
        pool = multiprocessing.get_context("spawn").Pool(workers)      # the workers start here, with that env
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    with pool:
        return dict(pool.map(_blind_diagnosis, BLIND_CASES, chunksize=1))


def _named_ok(d, truth):
    if d.verdict == "named":
        return d.named == [truth]
    if d.verdict == "ambiguous":       # allowed only between pairs the report declares confusable
        declared = {frozenset((a, b)) for a, b, _ in d.confusable}
        return truth in d.named and all(frozenset((truth, o)) in declared for o in d.named if o != truth)
    return False


@pytest.mark.slow
def test_null_data_give_no_discrepancy(blind):
    d = blind["none"]
    assert d.verdict == "none" and d.named == [] and d.final is None
    assert max(c.lr for c in d.candidates.values()) <= d.threshold


@pytest.mark.slow
@pytest.mark.parametrize("truth", ["time_delay", "fractional_transport"])
def test_hidden_library_effect_is_named_and_the_gap_shrinks(blind, truth):
    d = blind[truth]
    assert _named_ok(d, truth), (d.verdict, d.named, d.message)
    assert gap_shrink(d) >= 5.0
    assert d.gap_after["cost"] < d.gap_before["cost"] / 5
    ne = d.named_effect()[truth]
    for v in ne.values():
        assert v["ci95"][0] <= v["value"] <= v["ci95"][1]


@pytest.mark.slow
def test_out_of_library_effect_ends_unexplained(blind):
    d = blind["fixture_resonance"]
    assert "fixture_resonance" in OUT_OF_LIBRARY
    assert d.verdict == "unexplained", d.message
    assert d.named == []
    assert any(r["flagged"] for r in d.localisation_before)


@pytest.mark.slow
def test_two_hidden_effects_are_named_greedily(blind):
    d = blind["two"]
    assert d.verdict == "named", d.message
    assert sorted(d.named) == ["fractional_transport", "time_delay"]


@pytest.mark.slow
def test_report_folder(blind, tmp_path):
    d = blind["time_delay"]
    d.write_report(tmp_path / "rep")
    rep = json.loads((tmp_path / "rep" / "report.json").read_text())
    assert rep["verdict"] in VERDICTS and rep["named_effect"]
    assert set(rep["candidates"]) >= {"time_delay", "amplifier_bandwidth", "fractional_transport", "series_cpe"}
    assert rep["temperature_laws"].startswith("those of the parameter set")
    assert [r["name"] for r in rep["baseline_parameters"]] == list(FREE)
    assert all(r["plausible"] != "none" for r in rep["baseline_parameters"] if r["name"] != "alpha0")
    assert rep["baseline_audit"]["multistart"]["n_starts"] == 3
    for key in ("lr", "aic", "bic", "significant", "values", "ci95_lower"):
        assert key in rep["candidates"]["time_delay"]
    assert rep["gap_before"]["cost"] > rep["gap_after"]["cost"]
    assert len(rep["gap_after"]["rms_db"]) == len(T) and rep["localisation_before"]
    assert {"a": "amplifier_bandwidth", "b": "time_delay"} in [{k: p[k] for k in ("a", "b")} for p in rep["confusable_pairs"]]
    assert all(p["what_separates"] for p in rep["confusable_pairs"])
    summ = (tmp_path / "rep" / "summary.md").read_text()
    assert "NAMED" in summ and "## Baseline parameters" in summ and "Multi-start" in summ
    assert "Temperature laws:" in summ
    from scenarios.plots import diagnosis_figures

    diagnosis_figures(d, tmp_path / "rep")
    for png in ("bode_before.png", "bode_after.png"):
        assert (tmp_path / "rep" / png).read_bytes()[:4] == b"\x89PNG"
    assert not list((tmp_path / "rep").glob("*.tmp*"))


@pytest.mark.slow
def test_sensor_amplifier_pole_is_named():
    ps = get_parameter_set("seed000_sensor_dev")
    rng = np.random.default_rng(np.random.SeedSequence(SEALED, spawn_key=(99,)))
    tau = rng.uniform(1e-3, 2e-3)
    data = synthesize_sweep(EffectModel(ps, "sensor", {"amplifier_bandwidth": {"time_constant": tau}}), "S",
                            np.logspace(1, 2, 20), [25, 45, 65], MagnitudePhaseNoise(0.2, 1.0), seed=int(rng.integers(2**31)))
    d = diagnose(data, ps, kind="sensor", free=("a0", "d"), seed=1, null_refits=2)
    assert _named_ok(d, "amplifier_bandwidth"), d.message
    # the two poles are symmetric (1/((1 + sτa)(1 + sτb))): which one ends as the dominant one's name
    # depends on the optimiser's path, which differs with the numpy/scipy build (lowest versions: the
    # dominant pole came out as second_time_constant), so the pole near the truth is the one checked
    names = ("amplifier_bandwidth.time_constant", "amplifier_bandwidth.second_time_constant")
    dom = max(names, key=lambda n: d.final.values[n])
    fitted = d.final.values[dom]
    assert d.final.ci_lower[dom] <= tau <= d.final.ci_upper[dom] or abs(fitted / tau - 1) < 0.05


def test_linearised_null_gives_the_chi_bar_squared_boundary_mixture():
    # one parameter with its "off" value at a bound: LR ~ ½χ²0 + ½χ²1, 95 % point 2.71 (discrepancy.md §3);
    # two-sided: χ²1, 3.84.
    rng = np.random.default_rng(3)
    S = rng.standard_normal((40, 1))
    E = rng.standard_normal((40, 40000))
    assert np.quantile(constrained_lr(S, np.array([True]), E), 0.95) == pytest.approx(2.706, abs=0.12)
    assert np.quantile(constrained_lr(S, np.array([False]), E), 0.95) == pytest.approx(3.841, abs=0.15)
    assert np.mean(constrained_lr(S, np.array([True]), E) == 0) == pytest.approx(0.5, abs=0.01)
    # two one-sided parameters, orthogonal: ¼χ²0 + ½χ²1 + ¼χ²2, 95 % point 4.23
    S2 = np.linalg.qr(rng.standard_normal((40, 2)))[0]
    assert np.quantile(constrained_lr(S2, np.array([True, True]), E), 0.95) == pytest.approx(4.231, abs=0.15)


@pytest.mark.slow
def test_a_candidate_at_its_bound_is_never_a_confident_name():
    """Hidden contact resistance 3e-3 Ω·m² with the candidate bound set to 1e-3 (issue 11, cause 1):
    diffusivity_temperature (declared confusable) then closes the gap, but the report says that
    contact_resistance stopped at its bound (widen it) instead of naming confidently; with the
    strip-scaled bound contact_resistance is named."""
    data, _ = _hidden(21, lambda r: {"contact_resistance": {"r2_specific": 3e-3}})
    tight = diagnose(data, P, kind="actuator", free=FREE, seed=0, null_refits=0,
                     candidate_bounds={"contact_resistance.r2_specific": (0.0, 1e-3)})
    assert tight.verdict in ("at_bound", "unexplained"), tight.message
    assert frozenset(("contact_resistance", "diffusivity_temperature")) in {frozenset(c[:2]) for c in tight.confusable}
    assert tight.candidates["contact_resistance"].values["r2_specific"] == pytest.approx(1e-3, rel=1e-3)
    assert "contact_resistance.r2_specific" in tight.message and "bound" in tight.message and "widen" in tight.message
    free = diagnose(data, P, kind="actuator", free=FREE, seed=0, null_refits=0)
    assert _named_ok(free, "contact_resistance"), free.message
    cr = free.candidates["contact_resistance"]
    assert cr.ci_lower["r2_specific"] <= 3e-3 <= cr.ci_upper["r2_specific"] and not cr.at_bound


@pytest.mark.slow
def test_temperature_laws_are_chosen_and_stated():
    from physmodel.temperature import ISOTHERMAL

    iso = P.replace(laws=ISOTHERMAL)
    data = synthesize_sweep(EffectModel(iso, "actuator"), "M", F, T, MagnitudePhaseNoise(0.2, 1.0), seed=5)
    d = diagnose(data, P, kind="actuator", free=FREE, seed=0, null_refits=0, laws="isothermal")
    assert d.verdict == "none", d.message
    assert "isothermal" in d.laws
    d2 = diagnose(data, P, kind="actuator", free=FREE, seed=0, null_refits=0,
                  laws={"base": "isothermal", "d": {"law": "Arrhenius", "activation_energy": 20e3}})
    assert "Arrhenius(activation_energy=20000)" in d2.laws and d2.verdict != "none"   # the wrong law shows
    with pytest.raises(ParameterError, match="laws"):
        diagnose(data, P, free=FREE, laws="warm")
    with pytest.raises(ParameterError, match="no temperature law"):
        diagnose(data, P, free=FREE, laws={"viscosity": "Constant"})


@pytest.mark.slow
def test_cost_inconsistent_with_the_declared_noise_is_reported_with_its_factor():
    data = synthesize_sweep(EffectModel(P, "actuator"), "M", F, T, MagnitudePhaseNoise(0.05, 0.3), seed=8)
    big = type(data)(**{**data.__dict__, "magnitude_std_db": data.magnitude_std_db * 10,
                        "phase_std_deg": data.phase_std_deg * 10})
    d = diagnose(big, P, kind="actuator", free=FREE, seed=0, null_refits=0)
    assert d.cost_warning.startswith("too low") and "Cost vs declared noise" in d.message
    factor = float(d.cost_warning.split("about ")[1].split("×")[0])
    assert 7 < factor < 14                               # the declared σ is 10× the true one
    ok = diagnose(data, P, kind="actuator", free=FREE, seed=0, null_refits=0)
    assert ok.cost_warning == ""


def test_a_baseline_outside_its_plausible_range_is_reported():
    """Data from a strip damped at ξ = 3 (outside the plausible [0.01, 1]): the baseline can only
    fit by leaving the range, and the report says that this is evidence of a missing effect."""
    from physmodel.estimation.records import FreeParameter

    data = synthesize_sweep(EffectModel(P.replace(xi=3.0), "actuator"), "M", F, T, MagnitudePhaseNoise(0.2, 1.0), seed=9)
    d = diagnose(data, P, kind="actuator", free=("alpha0", "d", FreeParameter("xi", 0.01, 10.0, "log", 0.18)),
                 seed=0, null_refits=0, candidates=["time_delay", "leakage"])
    names = [x["name"] for x in d.baseline_audit["implausible"]]
    assert names == ["xi"] and "plausible range of xi" in d.message
    assert d.baseline_audit["penalty"] > 0


def test_bad_input_is_named():
    data = synthesize_sweep(EffectModel(P, "actuator"), "M", F[:10], [25.0], MagnitudePhaseNoise(0.1, 1.0), seed=1)
    with pytest.raises(IPMCError, match="alpha"):
        diagnose(data, P, alpha=0.7)
    with pytest.raises(ParameterError, match="unknown candidate"):
        diagnose(data, P, candidates=["fixture_resonance"])
    with pytest.raises(ParameterError, match="does not apply"):
        diagnose(data, P, candidates=["coupling_compliance"])
    with pytest.raises(IPMCError, match="null_draws"):
        diagnose(data, P, null_draws=10)
    with pytest.raises(ParameterError, match="absolute bounds"):
        diagnose(data, P, candidate_bounds={"contact_resistance.r2_specific": (0.0, 50.0)})
    with pytest.raises(ParameterError, match="expected 'effect.parameter'"):
        diagnose(data, P, candidate_starts={"leakage": 3.0})
    with pytest.raises(ParameterError, match="plausible range"):
        diagnose(data, P, plausible={"kappa_e": (1e-5, 1e-7)})


def test_cli_writes_the_report_and_rejects_bad_input(tmp_path):
    from scenarios.commands import diagnose as discrepancy_cli

    data, _ = _hidden(7, lambda r: {"amplifier_bandwidth": {"time_constant": 2e-3}})
    data.to_csv(tmp_path / "sweep.csv")
    (tmp_path / "exp.toml").write_text(
        'data = "sweep.csv"\nkind = "actuator"\nset = "seed002_table3"\nfree = ["alpha0", "d", "xi", "omega_n"]\n'
        'candidates = ["time_delay", "amplifier_bandwidth", "electrode_resistance"]\nnull_refits = 1\n'
        f'out = "{tmp_path / "out"}"\n[geometry]\nW = 2e-3\n')
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    discrepancy_cli.add_parser(sub)
    args = parser.parse_args(["diagnose", str(tmp_path / "exp.toml"), "--quiet"])
    assert args.func(args) == 0
    rep = json.loads((tmp_path / "out" / "report.json").read_text())
    assert rep["verdict"] in ("named", "ambiguous") and "amplifier_bandwidth" in rep["named"]
    args = parser.parse_args(["diagnose", str(tmp_path / "exp.toml"), "--quiet", "--laws", "isothermal",
                              "--law", "d=Arrhenius:activation_energy=15e3", "--candidate-bound",
                              "electrode_resistance.r1_sheet=0:500", "--candidate-start", "time_delay.delay=1e-3",
                              "--plausible", "d=1e-12:1e-10", "--baseline-starts", "2", "--out", str(tmp_path / "o2")])
    # the exit code says whether the model diagnose ends with fits the data, as its model.json does
    rc = args.func(args)
    assert rc == (0 if json.loads((tmp_path / "o2" / "model.json").read_text())["verdict"]["adequate"] else 3)
    rep = json.loads((tmp_path / "o2" / "report.json").read_text())
    assert "Arrhenius(activation_energy=15000)" in rep["temperature_laws"] and "E LogLinear" not in rep["temperature_laws"]
    assert rep["candidates"]["electrode_resistance"]["candidate_bounds"]["r1_sheet"] == [0.0, 500.0]
    assert rep["baseline_audit"]["plausible_ranges"]["d"].startswith("[1e-12, 1e-10]")
    import json as _json

    d = P.to_dict()
    d.pop("laws")
    (tmp_path / "nolaws.json").write_text(_json.dumps({k: v for k, v in d.items()}))
    bad = parser.parse_args(["diagnose", "--data", str(tmp_path / "sweep.csv"), "--set", str(tmp_path / "nolaws.json"),
                             "--quiet"])
    with pytest.raises(IPMCError, match="no 'laws'"):
        bad.func(bad)
    bad = parser.parse_args(["diagnose", "--data", str(tmp_path / "missing.csv"), "--set", "seed002_table3", "--quiet"])
    with pytest.raises(IPMCError):
        bad.func(bad)
    (tmp_path / "bad.toml").write_text('data = "sweep.csv"\nset = "seed002_table3"\nbogus = 1\n')
    bad = parser.parse_args(["diagnose", str(tmp_path / "bad.toml"), "--quiet"])
    with pytest.raises(IPMCError, match="bogus"):
        bad.func(bad)


@pytest.mark.slow
def test_a_baseline_stuck_short_of_its_optimum_is_refitted_not_taken_for_an_effect(monkeypatch, blind):
    """The first baseline fit is held away from its optimum (d confined to 1.6× the start, as a
    multi-start that missed the best basin would leave it); every candidate refit from there then
    "explains" the difference.  The workflow must notice that the baseline alone, refitted from a
    candidate's base values, does as well, and restart with it: on null data the verdict is 'none'
    and the baseline cost is the one of an unhindered fit."""
    import dataclasses

    import physmodel.estimation.discrepancy as disc

    data, _ = _hidden(0, BLIND_CASES["none"])
    original = disc.PenalisedProblem.fit
    calls = {"n": 0}

    def first_fit_held_away(self, free, **kw):
        calls["n"] += 1
        if calls["n"] == 1:
            free = [dataclasses.replace(fp, lower=1.6 * fp.initial, upper=1.601 * fp.initial, initial=1.6005 * fp.initial)
                    if fp.name == "d" else fp for fp in free]
        return original(self, free, **kw)

    monkeypatch.setattr(disc.PenalisedProblem, "fit", first_fit_held_away)
    d = diagnose(data, P, kind="actuator", free=FREE, seed=0, null_refits=0)
    restart = d.metadata["baseline_restart"]
    assert restart["cost_before"] > restart["cost_after"] + 10
    assert d.verdict == "none", d.message
    # the unhindered fit of the same data: blind["none"]'s baseline (the baseline fit comes before the
    # null calibration, so null_refits does not change it)
    assert d.baseline.cost == pytest.approx(blind["none"].baseline.cost, abs=1e-3)


@pytest.mark.slow
def test_a_second_effect_that_only_takes_a_share_of_the_noise_is_not_named():
    """A 3 ms delay with a weak fractional transport (β = 0.97, noiseless λ 89 on top of the fitted
    delay at 0.2 dB / 1°).  In this draw the fitted delay absorbs most of the transport and leaves
    2·cost just above the strict gap threshold; second_mode then takes LR 11 (> T ≈ 9) of the ≈ 44
    left above the χ² expectation and the pair closes strictly.  A second name needs more than
    that (found by this case: it was named before the majority rule); every name must be true."""
    data, _ = _hidden(7, lambda r: {"time_delay": {"delay": 3e-3}, "fractional_transport": {"beta": 0.97}})
    d = diagnose(data, P, kind="actuator", free=FREE, seed=0)
    assert "time_delay" in d.named and set(d.named) <= {"time_delay", "fractional_transport", "amplifier_bandwidth"}
    rejected = [p for p in d.metadata["pairs_tried"] if "second_mode" in p["pair"]]
    assert rejected and not any(p["accepted"] for p in rejected)
