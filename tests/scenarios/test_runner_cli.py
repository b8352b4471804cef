"""``ipmc run`` / ``ipmc demo``: strict schema errors (exit 2, naming key and file, nothing written),
failed checks (exit 3, FAIL in the report), interruption (exit 130, no report, no partial files)."""

from __future__ import annotations

import textwrap

import pytest

from scenarios.cli import main
from scenarios.spec import ScenarioError, load_scenario

SMALL = """
[scenario]
name = "small"
[model]
kind = "actuator"
set = "seed002_table3"
[widths]
widths_m = [4e-3, 1e-3]
points = 20
[checks.w]
metric = "widths.max_rel_change"
max = {bound}
"""


def _write(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


def test_run_passing_scenario(tmp_path, capsys):
    p = _write(tmp_path, SMALL.format(bound="1e-12"))
    assert main(["run", str(p), "--out", str(tmp_path / "o")]) == 0
    assert "1/1 checks passed" in capsys.readouterr().out
    assert "| w | PASS |" in (tmp_path / "o" / "report.md").read_text()


def test_failed_check_exits_3_and_says_fail(tmp_path, capsys):
    p = _write(tmp_path, SMALL.format(bound="-1"))
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--quiet"]) == 3
    assert "| w | FAIL |" in (tmp_path / "o" / "report.md").read_text()


@pytest.mark.parametrize("edit,needle", [
    (("[widths]", "[widhts]"), "unknown table [widhts]"),
    (("points = 20", "pionts = 20"), "unknown key 'pionts'"),
    (("points = 20", "points = \"many\""), "[widths].points: expected an integer"),
    (("kind = \"actuator\"", "kind = \"motor\""), "[model].kind: expected one of"),
    (("set = \"seed002_table3\"", ""), "missing required key 'set'"),
    (("metric = \"widths.max_rel_change\"", "metric = \"taylor.order_3_max_db_error\""), "refers to [taylor]"),
    (("max = -1", ""), "needs min and/or max"),
])
def test_schema_errors_name_the_key_and_file_and_exit_2(tmp_path, capsys, edit, needle):
    text = SMALL.format(bound="-1").replace(*edit)
    p = _write(tmp_path, text)
    out = tmp_path / "o"
    assert main(["run", str(p), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert needle in err and str(p) in err
    assert not out.exists()


def test_quick_table_is_validated_and_merged(tmp_path):
    base = SMALL.format(bound="1") + "\n[quick]\nwidths = { points = 5 }\n"
    assert load_scenario(_write(tmp_path, base), quick=True).section("widths")["points"] == 5
    assert load_scenario(_write(tmp_path, base), quick=False).section("widths")["points"] == 20
    with pytest.raises(ScenarioError, match=r"\[quick.taylor\] shrinks a table"):
        load_scenario(_write(tmp_path, SMALL.format(bound="1") + "\n[quick]\ntaylor = { points = 5 }\n"))
    with pytest.raises(ScenarioError, match="unknown key 'pts'"):
        load_scenario(_write(tmp_path, SMALL.format(bound="1") + "\n[quick]\nwidths = { pts = 5 }\n"))


def test_missing_and_malformed_files(tmp_path, capsys):
    assert main(["run", str(tmp_path / "nope.toml")]) == 2
    assert "neither a file nor a bundled scenario" in capsys.readouterr().err
    assert main(["run", str(_write(tmp_path, "a = [1,"))]) == 2
    assert "not valid TOML" in capsys.readouterr().err


def test_interrupt_leaves_no_report_and_no_partial_files(tmp_path, monkeypatch, capsys):
    import scenarios.runner as R

    out = tmp_path / "o"
    p = _write(tmp_path, SMALL.format(bound="1e-12"))
    assert main(["run", str(p), "--out", str(out), "--quiet"]) == 0        # a complete earlier run
    assert (out / "report.md").exists()
    before = {f.relative_to(out): f.read_bytes() for f in out.rglob("*") if f.is_file()}

    def boom(ctx):
        raise KeyboardInterrupt

    monkeypatch.setitem(R.STEPS, "widths", boom)
    assert main(["run", str(p), "--out", str(out), "--quiet"]) == 130
    assert "interrupted" in capsys.readouterr().err
    # all or nothing (issue 28): the folder still holds the earlier complete result, byte for byte,
    # and no temporary folder or file is left next to it
    assert {f.relative_to(out): f.read_bytes() for f in out.rglob("*") if f.is_file()} == before
    assert not [f for f in tmp_path.rglob("*") if f.name.endswith(".part")]


def test_interrupt_inside_a_figure_write_leaves_no_file(tmp_path, monkeypatch):
    """atomic_write: an interruption while a file is being written leaves neither it nor its temp file."""
    import scenarios.plots as P

    def broken_savefig(self, fh, **kw):
        fh.write(b"\x89PNG half")
        raise KeyboardInterrupt

    monkeypatch.setattr("matplotlib.figure.Figure.savefig", broken_savefig)
    out = tmp_path / "o"
    p = _write(tmp_path, SMALL.format(bound="1e-12"))
    assert main(["run", str(p), "--out", str(out), "--quiet"]) == 130
    assert not (out / "widths.png").exists() and not (out / "report.md").exists()
    assert not [f for f in out.rglob("*") if f.name.endswith(".part")]
    assert P is not None


def test_run_finds_bundled_scenarios_by_name(tmp_path, capsys):
    assert main(["run", "--list"]) == 0
    assert "seed000_sensor" in capsys.readouterr().out
    assert main(["run"]) == 2
    assert main(["run", "seed002_structure", "--quick", "--quiet", "--out", str(tmp_path / "o")]) == 0


def test_every_command_has_help(capsys):
    for cmd in ("run", "demo", "study"):
        with pytest.raises(SystemExit) as e:
            main([cmd, "--help"])
        assert e.value.code == 0
        assert "--quiet" in capsys.readouterr().out


def test_a_non_converged_fit_is_reported_and_fails_the_run(tmp_path, monkeypatch):
    import dataclasses

    import surrogate

    real = surrogate.fit_sweep

    def flagged(*a, **k):
        return dataclasses.replace(real(*a, **k), converged=False, status="Maximum_Iterations_Exceeded")

    monkeypatch.setattr(surrogate, "fit_sweep", flagged)
    p = _write(tmp_path, """
        [scenario]
        name = "nc"
        [model]
        kind = "actuator"
        set = "seed002_table3"
        [sweep]
        temperatures_c = [20.0, 30.0, 40.0]
        fmin_hz = 1.0
        fmax_hz = 30.0
        points = 12
        [surrogate]
        form = "zpk"
        n_zeros = 1
        n_poles = 3
        degree = 1
        [checks.loose]
        metric = "surrogate.train_rel_rms_max"
        max = 10
        """)
    assert main(["run", str(p), "--out", str(tmp_path / "o"), "--quiet"]) == 3
    report = (tmp_path / "o" / "report.md").read_text()
    assert "NOT CONVERGED: Maximum_Iterations_Exceeded" in report
    assert "| surrogate_converged | FAIL |" in report and "| loose | PASS |" in report
