"""``ipmc validate``: every published claim covered, statuses with reasons, files and exit codes."""

from __future__ import annotations

import json

import pytest

from scenarios import validate as V
from scenarios.cli import main


@pytest.fixture(scope="module")
def report():
    return V.validate(quick=True)


@pytest.fixture(scope="module")
def claims():
    return V.published_claims(V.load_published())


def test_every_published_claim_has_one_row_in_file_order(report, claims):
    base = [cid for cid in report.claim_ids if "+" not in cid]
    assert base == [c[0] for c in claims]
    assert len(set(base)) == len(claims) > 40
    assert set(base) == set(V.CHECKS)                       # no stale mapping either
    extra = [cid for cid in report.claim_ids if "+" in cid]
    assert extra == [f"{k}+{e[0]}" for k, v in V.EXTRA_ROWS.items() for e in v]
    # an extra row follows its claim's row
    for cid in extra:
        i = report.claim_ids.index(cid)
        assert report.claim_ids[i - 1] == cid.split("+")[0]


def test_statuses_and_reasons(report):
    assert report.regressions == []
    for r in report.rows:
        assert r.status in V.STATUSES
        if r.status != "pass":
            assert len(r.reason) > 20, r.claim_id
        if r.status in ("pass", "not-reproduced"):
            assert r.ours not in ("", "-") and r.criterion not in ("", "-"), r.claim_id
    by = {r.claim_id: r for r in report.rows}
    for cid in ("sensor_seed000.trends_with_rising_temperature[0]", "sensor_seed000.trends_with_rising_temperature[1]",
                "sensor_seed000.trends_with_rising_temperature[2]", "actuator_seed001.trends[0]",
                "actuator_seed001.trends[1]", "actuator_seed001.nonminimum_phase", "actuator_seed001.order_claims[0]",
                "actuator_seed002.claims[1]", "actuator_seed002.claims[2]", "actuator_seed002.claims[3]"):
        assert by[cid].status == "pass", (cid, by[cid].ours)
    assert by["sensor_seed000.model_35c_den"].status == "not-reproduced"
    assert by["sensor_seed000.model_order+nonminimum_phase"].status == "not-reproduced"
    assert by["sensor_seed000.model_order"].status == "pass"


def test_35c_misfit_in_table_matches_the_calibration_module(report):
    from physmodel import get_parameter_set
    from physmodel.parameter_sets.derivation import sensor_misfit_35c

    m = sensor_misfit_35c(get_parameter_set("seed000_sensor"))
    by = {r.claim_id: r for r in report.rows}
    assert f"RMS {m.rms_db:.2f} dB, max {m.max_db:.2f} dB" in by["sensor_seed000.model_35c_num"].ours
    assert f"RMS {m.rms_deg:.1f} deg, max {m.max_deg:.1f} deg" in by["sensor_seed000.model_35c_den"].ours
    assert report.metadata["sensor_misfit_35c"]["rms_db"] == pytest.approx(m.rms_db)


def test_markdown_and_json(report):
    md = report.to_markdown()
    assert md.count("\n| `") == len(report.rows)
    for cid in report.claim_ids:
        assert f"`{cid}`" in md
    d = json.loads(report.to_json())
    assert d["counts"] == report.counts and len(d["rows"]) == len(report.rows)


def _mini_toml(tmp_path, extra: str = "") -> str:
    (tmp_path / "seeds").mkdir()
    (tmp_path / "seeds" / "002.txt").write_text("x")
    (tmp_path / "data").mkdir()
    path = tmp_path / "data" / "published.toml"
    path.write_text('[actuator_seed002]\npaper = "002.txt"\nclaims = ["first vibration mode near 10 Hz"]\n'
                    + extra, encoding="utf-8")
    return str(path)


def test_unmapped_claim_fails_and_cli_exits_3(tmp_path):
    pub = _mini_toml(tmp_path, 'new_claim = "a claim nobody mapped"\n')
    rep = V.validate(published=pub)
    assert [r.status for r in rep.rows[:2]] == ["pass", "pass"]
    last = rep.rows[-1]
    assert last.claim_id == "actuator_seed002.new_claim" and last.status == "fail"
    assert "no check is mapped" in last.reason
    assert main(["validate", "--published", pub, "--out", str(tmp_path / "o"), "--quiet"]) == 3
    assert (tmp_path / "o" / "validation.json").is_file()


def test_regression_is_fail_and_finding_that_passes_is_pass(tmp_path, monkeypatch):
    pub = _mini_toml(tmp_path)
    bad = lambda ctx, value: V.Outcome("1", "2", False)  # noqa: E731
    monkeypatch.setitem(V.CHECKS, "actuator_seed002.claims[0]", (bad, "reproduce", "x"))
    rep = V.validate(published=pub)
    assert [r.status for r in rep.rows] == ["pass", "fail"] and "regression" in rep.rows[1].reason
    good = lambda ctx, value: V.Outcome("1", "2", True)  # noqa: E731
    monkeypatch.setitem(V.CHECKS, "actuator_seed002.claims[0]", (good, "finding: why", "x"))
    assert [r.status for r in V.validate(published=pub).rows] == ["pass", "pass"]


def test_cli_writes_files(tmp_path, capsys):
    out = tmp_path / "val"
    assert main(["validate", "--out", str(out), "--quick"]) == 0
    md = (out / "validation.md").read_text(encoding="utf-8")
    d = json.loads((out / "validation.json").read_text(encoding="utf-8"))
    assert md.startswith("# Validation") and d["format"] == "ipmc-validation"
    assert d["counts"]["fail"] == 0 and len(d["rows"]) == sum(d["counts"].values())
    assert "wrote" in capsys.readouterr().out
    assert not list(out.glob("*.part"))


def test_cli_bad_input(tmp_path, capsys):
    assert main(["validate", "--published", str(tmp_path / "missing.toml"), "--quiet"]) == 2
    assert "does not exist" in capsys.readouterr().err
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["validate", "--out", str(f), "--quiet", "--published", _mini_toml(tmp_path)]) == 2
