"""Issue 28: result folders are written all or nothing and later commands refuse an incomplete
one, naming it (the rule: physmodel/data/results.py and docs/cli.md)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from physmodel.data import results
from physmodel.errors import IPMCError
from scenarios.cli import main

sys.path.insert(0, str(Path(__file__).parent))
import fuzzcases  # noqa: E402


@pytest.fixture(scope="module")
def cal(tmp_path_factory):
    """A complete calibration folder (and its sweep)."""
    d = tmp_path_factory.mktemp("cal")
    fuzzcases.valid_sweep(d, "sweep.csv", temps=(20.0, 40.0), points=12)
    assert main(["calibrate", str(d / "sweep.csv"), "--set", "seed002_table3", "--free", "d", "--starts", "1",
                 "--out", str(d / "cal"), "--quiet"]) == 0
    return d / "cal"


def _sweep_from(params: Path, tmp_path) -> int:
    return main(["sweep", "--params-json", str(params), "--points", "5", "--out", str(tmp_path / "s.csv"), "--quiet"])


def test_a_complete_folder_has_the_marker_listing_its_files(cal):
    mark = json.loads((cal / results.MARKER).read_text())
    assert mark["format"] == "ipmc-result" and mark["command"] == "ipmc calibrate"
    assert mark["files"] == sorted(p.name for p in cal.iterdir() if p.name != results.MARKER)


def test_a_folder_left_by_an_interrupted_older_version_is_refused(cal, tmp_path, capsys):
    """What the issue found: a folder holding only parameters.json (written by calibrate, no report)."""
    legacy = tmp_path / "old"
    legacy.mkdir()
    (legacy / "parameters.json").write_bytes((cal / "parameters.json").read_bytes())
    assert _sweep_from(legacy / "parameters.json", tmp_path) == 2
    err = capsys.readouterr().err
    assert str(legacy) in err and "--params-json" in err and "interrupted" in err
    # ... and --model on a model.json of such a folder
    (legacy / "model.json").write_bytes((cal / "model.json").read_bytes())
    assert main(["sweep", "--model", str(legacy / "model.json"), "--points", "5", "--out", str(tmp_path / "m.csv"),
                 "--quiet"]) == 2
    assert str(legacy) in capsys.readouterr().err
    # the same files with the report an older version wrote last: complete, accepted
    (legacy / "report.md").write_text("# report\n")
    assert _sweep_from(legacy / "parameters.json", tmp_path) == 0


def test_a_temporary_folder_and_a_broken_marker_are_refused(cal, tmp_path, capsys):
    stage = tmp_path / ".cal.123.abcd.part"
    stage.mkdir()
    (stage / "parameters.json").write_bytes((cal / "parameters.json").read_bytes())
    assert _sweep_from(stage / "parameters.json", tmp_path) == 2
    assert "temporary folder" in capsys.readouterr().err
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "parameters.json").write_bytes((cal / "parameters.json").read_bytes())
    (broken / results.MARKER).write_text("{not json")
    assert _sweep_from(broken / "parameters.json", tmp_path) == 2
    assert "completion marker" in capsys.readouterr().err


def test_a_parameter_file_written_by_hand_needs_no_marker(tmp_path):
    from physmodel import get_parameter_set, save_parameter_set

    save_parameter_set(get_parameter_set("seed002_table3"), tmp_path / "mine.json")
    assert _sweep_from(tmp_path / "mine.json", tmp_path) == 0


def test_a_complete_folder_is_accepted_downstream(cal, tmp_path):
    assert _sweep_from(cal / "parameters.json", tmp_path) == 0


def test_a_failing_block_leaves_the_previous_result_and_no_temporary_folder(tmp_path):
    out = tmp_path / "r"
    with results.output_folder(out, "ipmc test") as st:
        (st / "a.txt").write_text("first")
    assert (out / "a.txt").read_text() == "first" and (out / results.MARKER).exists()
    with pytest.raises(RuntimeError):
        with results.output_folder(out, "ipmc test") as st:
            (st / "a.txt").write_text("second")
            raise RuntimeError("boom")
    assert (out / "a.txt").read_text() == "first"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]


def test_replacing_a_result_keeps_the_users_own_files_but_not_the_old_results(tmp_path):
    out = tmp_path / "r"
    with results.output_folder(out, "ipmc test") as st:
        (st / "old_figure.png").write_text("x")
        (st / "a.txt").write_text("1")
    (out / "notes.txt").write_text("mine")                       # the user's file, not in the marker
    with results.output_folder(out, "ipmc test") as st:
        (st / "a.txt").write_text("2")
    assert sorted(p.name for p in out.iterdir()) == [results.MARKER, "a.txt", "notes.txt"]
    assert (out / "notes.txt").read_text() == "mine" and (out / "a.txt").read_text() == "2"


def test_another_commands_folder_is_refused_and_a_busy_folder_too(tmp_path):
    out = tmp_path / "r"
    with results.output_folder(out, "ipmc one") as st:
        (st / "a.txt").write_text("1")
    with pytest.raises(IPMCError, match="--force"):
        with results.output_folder(out, "ipmc two"):
            pass
    with results.output_folder(out, "ipmc one"):
        with pytest.raises(IPMCError, match="another ipmc run is writing"):
            with results.output_folder(out, "ipmc one"):
                pass


def test_an_output_folder_under_a_file_or_unwritable_parent_is_refused_before_work(tmp_path):
    (tmp_path / "f").write_text("")
    with pytest.raises(IPMCError, match="not a folder"):
        results.check_output_folder(tmp_path / "f" / "out", "ipmc x")
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        import os

        if os.access(ro, os.W_OK):                               # root ignores the mode
            pytest.skip("running as a user who can write anywhere")
        with pytest.raises(IPMCError, match="permission denied"):
            results.check_output_folder(ro / "out", "ipmc x")
    finally:
        ro.chmod(0o700)


def test_a_stale_temporary_folder_of_a_killed_run_is_cleaned_by_the_next(tmp_path):
    out = tmp_path / "r"
    stale = tmp_path / ".r.999999.dead.part"                    # SIGKILL leaves this (no lock held)
    stale.mkdir()
    (stale / "half.json").write_text("{")
    with results.output_folder(out, "ipmc test") as st:
        (st / "a.txt").write_text("1")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r"]


def test_an_output_folder_that_is_the_working_directory_is_updated_in_place(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "input.csv").write_text("keep")
    with results.output_folder(Path("."), "ipmc test", force=True) as st:
        (st / "a.txt").write_text("1")
    assert Path.cwd() == tmp_path and (tmp_path / "input.csv").read_text() == "keep"
    assert (tmp_path / "a.txt").read_text() == "1" and (tmp_path / results.MARKER).exists()


def test_whose_results_an_unmarked_folder_holds(tmp_path):
    """Folders of older versions (no marker) are still recognised by their files."""
    cases = {"diag": (("report.json", {"verdict": "adequate"}), ("model.json", {})),
             "ff": (("report.json", {"peak_voltage_V": 1.0}),), "fit": (("model.json", {}),),
             "cal": (("calibration.json", {}), ("model.json", {})), "run": (("metrics.json", {"scenario": "s"}),)}
    want = {"diag": "ipmc diagnose", "ff": "ipmc feedforward", "fit": "ipmc fit", "cal": "ipmc calibrate",
            "run": "ipmc run s"}
    for name, files in cases.items():
        (tmp_path / name).mkdir()
        for f, d in files:
            (tmp_path / name / f).write_text(json.dumps(d))
        assert results.folder_owner(tmp_path / name) == want[name], name
