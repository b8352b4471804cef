"""The [next_measurement] scenario step measures every recommended record: when the search
recommends a second one (``NextMeasurement.also``, issue 27) the virtual lab takes it too, with
its own noise seed and none of the lines already held, and the three are diagnosed together."""

from __future__ import annotations

import numpy as np


def test_the_virtual_lab_takes_the_second_recommended_record(tmp_path, second_recommended_record):
    """The bundled demo with the recommendation given a second record (1-9 Hz at the record's 35 °C,
    below the first record's band — a record no search chose here, added by the test so that the
    step's handling is checked on a fast bundled case): record3.csv holds it, in its band and
    sharing no line with records 1 and 2, and the summary's table counts three records."""
    from physmodel.data.files import read_csv
    from scenarios.runner import run_scenario
    from scenarios.spec import bundled_scenarios, load_scenario

    path = [p for p in bundled_scenarios() if p.stem == "next_measurement_demo"][0]
    run_scenario(load_scenario(path, quick=True), tmp_path / "run", quiet=True)
    out = tmp_path / "run" / "next_measurement"
    recs = [read_csv(out / f"record{i}.csv") for i in (1, 2, 3)]
    r3 = recs[2]
    assert r3.frequency_hz.size > 0 and r3.frequency_hz.min() >= 1.0 - 1e-9 and r3.frequency_hz.max() <= 9.0 + 1e-9
    assert np.all(r3.temperature_c == 35.0)
    held = {(float(t), float(f)) for r in recs[:2] for t, f in zip(r.temperature_c, r.frequency_hz)}
    assert not held & {(float(t), float(f)) for t, f in zip(r3.temperature_c, r3.frequency_hz)}
    text = " ".join(p.read_text(encoding="utf-8") for p in (tmp_path / "run").glob("*.md"))
    assert "1 + 2 + 3: adds" in text


def test_two_records_short_of_the_target_are_taken_and_the_shortfall_said(tmp_path, capsys, monkeypatch,
                                                                          second_recommended_record):
    """The same, with the two records offered short (``also`` set, ``separates`` False — the best
    plan when no pair of records reaches the target after the refits): the virtual lab takes both
    all the same, and the table, stderr and metrics.json say the shortfall against the target."""
    import json

    from physmodel.estimation.diagnosis import Diagnosis
    from scenarios.runner import run_scenario
    from scenarios.spec import bundled_scenarios, load_scenario

    with_second = Diagnosis.recommend_next_measurement

    def short(self, **kw):
        nm = with_second(self, **kw)
        nm.separates = False
        nm.together["separation"] = 0.5 * nm.target        # a stated λ: half the target
        return nm

    monkeypatch.setattr(Diagnosis, "recommend_next_measurement", short)
    path = [p for p in bundled_scenarios() if p.stem == "next_measurement_demo"][0]
    run_scenario(load_scenario(path, quick=True), tmp_path / "run", quiet=True)
    out = tmp_path / "run" / "next_measurement"
    assert (out / "record3.csv").exists()
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text(encoding="utf-8"))["metrics"]
    target = metrics["next_measurement.target"]
    assert metrics["next_measurement.expected_to_separate"] in (0, False)
    assert metrics["next_measurement.short_by"] == 0.5 * target
    said = f"expected λ {0.5 * target:.3g} (short of {target:.3g} needed: not expected to separate)"
    assert said in capsys.readouterr().err
    text = " ".join(p.read_text(encoding="utf-8") for p in (tmp_path / "run").glob("*.md"))
    assert "1 + 2 + 3: adds" in text and f"{0.5 * target:.3g} (short of {target:.3g} needed" in text


def test_one_record_short_is_said_at_the_lesser_of_its_linearised_and_refit_lambda(tmp_path, capsys, monkeypatch):
    """A single recommended record not expected to separate whose refits give MORE than its
    linearisation (bench_next_measurement's 50688: 8.8 linearised, 264 after the refits): the step
    says it at the lesser, as the library's message does (review: it printed "expected λ 264 (short
    of 42 needed)" with short_by 0)."""
    import json
    from dataclasses import replace

    from physmodel.estimation.diagnosis import Diagnosis
    from scenarios.runner import run_scenario
    from scenarios.spec import bundled_scenarios, load_scenario

    real = Diagnosis.recommend_next_measurement

    def stated(self, **kw):
        nm = real(self, **kw)
        nm.recommended = replace(nm.recommended, separation=8.8, separation_refit=264.0)
        nm.separates, nm.also, nm.together = False, [], {}
        return nm

    monkeypatch.setattr(Diagnosis, "recommend_next_measurement", stated)
    path = [p for p in bundled_scenarios() if p.stem == "next_measurement_demo"][0]
    run_scenario(load_scenario(path, quick=True), tmp_path / "run", quiet=True)
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text(encoding="utf-8"))["metrics"]
    target = metrics["next_measurement.target"]
    assert metrics["next_measurement.expected_separation"] == 8.8
    assert metrics["next_measurement.short_by"] == target - 8.8
    assert f"expected λ 8.8 (short of {target:.3g} needed" in capsys.readouterr().err
