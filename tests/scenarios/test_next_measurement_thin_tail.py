"""The [next_measurement] step passes on its diagnoses' thin-null-tail note ("verdicts travel"):
the demo's ``--quick`` runs 400 null draws, which leave ceil(399 × 0.01) = 4 beyond the gap test's
0.99 quantile (one quantity, α = 0.05, α_gap = 0.01) — the top-level report.md (under the verdict
table), metrics.json and stderr say it, as ``ipmc diagnose`` does.  902 draws leave
ceil(901 × 0.01) = 10 and nothing is said."""

from __future__ import annotations

import json

import pytest


@pytest.mark.parametrize("draws, beyond", [(400, 4), (902, 10)])
def test_the_run_says_a_thin_null_tail(tmp_path, capsys, draws, beyond):
    from scenarios.runner import run_scenario
    from scenarios.spec import bundled_scenarios, load_scenario

    demo = [p for p in bundled_scenarios() if p.stem == "next_measurement_demo"][0].read_text(encoding="utf-8")
    quick = "next_measurement = { null_draws = 400, null_refits = 0 }"
    assert quick in demo
    path = tmp_path / "demo.toml"
    path.write_text(demo.replace(quick, quick.replace("400", str(draws))), encoding="utf-8")
    run_scenario(load_scenario(path, quick=True), tmp_path / "run", quiet=True)
    err = capsys.readouterr().err
    report = (tmp_path / "run" / "report.md").read_text(encoding="utf-8")
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text(encoding="utf-8"))["metrics"]
    assert metrics["next_measurement.null_tail_draws"] == beyond
    section = report.split("## The next measurement")[1].split("## Checks")[0]
    if draws == 400:
        note = f"Thin null tail: of the {draws} null draws, 4 beyond the gap threshold (its 0.99 quantile)"
        assert metrics["next_measurement.thin_null_tail"] == 1
        assert note in err and "Diagnosis 1 and 2: " + note in section, (err, section)
        assert section.index("| records diagnosed |") < section.index(note)          # under the verdict table
    else:
        assert metrics["next_measurement.thin_null_tail"] == 0
        assert "Thin null tail" not in err and "Thin null tail" not in report
