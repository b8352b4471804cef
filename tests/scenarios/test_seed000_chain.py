"""The ``seed000_chain`` scenario (issue 16), run quick with the ``[chain]`` step registered the way
the merge will register it.  Oracles: the printed coefficients' own roots (numpy.roots of the
published numerator), the steady-state decoding error A|P/G − 1| computed from the printed model and
the decoder's own transfer function, and the misfit recomputed directly from the written metrics."""

import json

import numpy as np
import pytest

from scenarios import runner, spec
from scenarios.spec import CHAIN_SCHEMA
from scenarios.steps_chain import (
    misfit,
    printed_response,
    printed_sweep,
    step_chain,
)


def _register(mp):
    """Register the [chain] step the way the merge did, unless it already is (registering it twice
    would run the step twice)."""
    if "chain" not in spec.STEP_ORDER:
        mp.setattr(spec, "STEP_ORDER", spec.STEP_ORDER + ("chain",))
    mp.setitem(spec.SECTIONS, "chain", CHAIN_SCHEMA)
    mp.setitem(runner.STEPS, "chain", step_chain)


@pytest.fixture
def registered(monkeypatch):
    _register(monkeypatch)


#: The fast tier's run: the bundled quick run with fewer lines, one candidate (the quick run's first
#: name), one greedy step, fewer null draws and starts (about 5 s of CPU instead of 45 s).  The tests
#: below assert oracles, invariants and consistency that hold at any size; the bundled quick run is
#: the slow tier's.
SMALL = {"points": 16, "candidates": ["tip_driven_beam"], "documented": ["tip_driven_beam"], "max_steps": 1,
         "null_draws": 200, "null_refits": 0, "baseline_starts": 1}


@pytest.fixture(scope="module", params=[pytest.param("small", id="small"),
                                        pytest.param("quick", id="quick", marks=pytest.mark.slow)])
def quick_result(request, tmp_path_factory):
    """The small run, or the bundled quick run (the session's, tests/conftest.py: test_scenarios.py
    asserts on the same run)."""
    import tomllib

    if request.param == "quick":
        return request.getfixturevalue("seed000_chain_quick")
    mp = pytest.MonkeyPatch()
    _register(mp)
    out = tmp_path_factory.mktemp(f"chain_{request.param}")
    try:
        path = spec.bundled_scenarios()[0].parent / "seed000_chain.toml"
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
        raw["quick"]["chain"] = {**raw["quick"]["chain"], **SMALL}
        res = runner.run_scenario(spec.parse_scenario(raw, str(path), quick=True), out, quiet=True)
    finally:
        mp.undo()
    return res, out


def test_scenario_passes_its_checks_and_writes_its_figures(quick_result):
    res, out = quick_result
    assert not [(c.name, c.value) for c in res.checks if not c.passed]
    assert list(spec.STEP_ORDER).count("chain") == 1
    for f in ("chain_bode.png", "chain_pole_zero.png", "chain_effects.png", "chain_a0_temperature.png",
              "chain_bode_temperatures.png", "metrics.json", "report.md"):
        assert (out / f).exists(), f
    rep = (out / "report.md").read_text()
    assert "Verdict: **" in rep and "Temperature series" in rep


def test_printed_model_fit_finds_the_printed_right_half_plane_zeros(quick_result):
    from physmodel.parameter_sets.published import seed000_printed_model_35c

    m = quick_result[0].metrics
    num, _, _ = seed000_printed_model_35c()
    assert m["chain.rhp_zeros.printed_model"] == int(np.sum(np.roots(num).real > 0)) == 3
    # the polymer alone (fitted to the same data) has none: the non-minimum phase is not the physics'
    assert m["chain.rhp_zeros.physics_alone"] == 0
    assert m["chain.rhp_zeros.chain_s_physics_part"] == 0


def test_decoding_errors_follow_the_steady_state_prediction(quick_result):
    m = quick_result[0].metrics
    for fr in ("20hz", "54hz"):
        for dec in ("physics_alone", "physics_chain", "documented_sourced_ranges"):
            err, pred = m[f"chain.decode_{fr}.{dec}_error_rel"], m[f"chain.decode_{fr}.{dec}_predicted_rel"]
            # up to what the inversion itself reports it adds by sampling, plus 5 % (as control_route)
            allow = m[f"chain.decode_{fr}.{dec}_sampling_bound_rel"] + 0.05 * pred
            assert abs(err - pred) <= allow, (fr, dec, err, pred, allow)


def test_misfit_is_what_it_says():
    data = printed_sweep()
    assert misfit(data.response, data.response)["rms_db"] < 1e-12
    assert misfit(2 * data.response, data.response)["max_db"] == pytest.approx(20 * np.log10(2), rel=1e-12)
    assert np.allclose(data.response, printed_response(data.frequency_hz))


def test_the_verdict_is_consistent_with_the_misfits(quick_result):
    m = quick_result[0].metrics
    assert m["chain.misfit_chain_rms_db"] < m["chain.misfit_physics_rms_db"]
    assert m["chain.named"] == (m["chain.closes_gap"] and m["chain.implausible_count"] == 0 and m["chain.plausible"])
    written = json.loads((quick_result[1] / "metrics.json").read_text())["metrics"]
    assert written["chain.misfit_documented_rms_deg"] == m["chain.misfit_documented_rms_deg"]


def test_chain_step_needs_a_sensor_model(registered, tmp_path):
    toml = tmp_path / "bad.toml"
    toml.write_text('[scenario]\nname = "bad"\n[model]\nkind = "actuator"\nset = "seed002_table3"\n[chain]\n'
                    'points = 11\n[checks.x]\nmetric = "chain.named"\nmin = 0\n')
    with pytest.raises(spec.ScenarioError, match="sensor"):
        runner.run_scenario(spec.load_scenario(toml), tmp_path / "out", quiet=True)


def test_temperature_series_has_estimates_intervals_and_misfits(quick_result):
    """The temperature step: every calibration reports finite values and intervals for the law parameters
    a0(T) depends on, its χ² and the a0 misfit; the 35 °C misfit is the chain fit's (laws are 1 there);
    the printed a0 ratio is recomputed from the printed polynomial coefficients."""
    from scenarios.steps_chain_temperature import VARIANTS, _slug

    m = quick_result[0].metrics
    for label, _beam, _water, names in VARIANTS:
        k = f"chain.temperature.{_slug(label)}"
        assert m[f"{k}.dof"] >= 4 and np.isfinite(m[f"{k}.chi2"]) and 0.0 <= m[f"{k}.p_value"] <= 1.0
        assert m[f"{k}.a0_misfit_max_pct"] >= m[f"{k}.a0_misfit_rms_pct"] > 0.0
        for n in names:
            p = f"{k}.{n.split('.', 1)[1].replace('.', '_')}"
            assert np.isfinite(m[p])
            if n != "laws.E.slope" or "beam" in label:       # E acts on a0 only through the beam's mode
                assert m[f"{p}_ci_lower"] <= m[p] <= m[f"{p}_ci_upper"], p
            else:
                assert not m[f"{p}_identifiable"]
        for t in ("cutoff_falls", "gain_falls", "lag_grows"):
            assert m[f"{k}.trend_{t}"] in (0, 1)
    for q in ("rms_db", "max_db", "rms_deg", "max_deg"):
        assert m[f"chain.temperature.misfit_35c_{q}"] == m[f"chain.misfit_chain_{q}"]
    c, x = np.array([4.81, -0.043, -0.00028, 8.56e-5]), np.array([23.0, 65.0]) - 23.07
    ratio = np.polyval(c[::-1], x[1]) / np.polyval(c[::-1], x[0])
    assert m["chain.temperature.a0_printed_ratio_65_23"] == pytest.approx(ratio, rel=1e-12)
    assert m["chain.temperature.d_35c"] == m["chain.chain.d"]
    assert "Temperature series: the polymer's laws with the chain fixed" in (quick_result[1] / "report.md").read_text()
