"""Two runs into one folder (issue 13, items 3 and 4): the second is refused while the first
writes, a finished run's folder is refused to another run unless --force, and a scenario name
cannot move the default folder out of the working directory."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from scenarios.cli import main

sys.path.insert(0, str(Path(__file__).parent))
import fuzzcases  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def _scenario(d: Path, name: str, points: int = 12) -> Path:
    doc = fuzzcases._deep(fuzzcases.MINI_SCENARIO)
    doc["scenario"]["name"] = name
    doc["sweep"]["points"] = points
    doc.pop("surrogate")
    return fuzzcases.write_scenario(d, doc, f"{name}.toml")


@pytest.mark.slow          # waits for a 400 000-point run to finish (about 10 s)
def test_a_second_job_into_a_busy_folder_is_refused(tmp_path):
    out = tmp_path / "Z"
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    slow = _scenario(tmp_path, "slow", points=400_000)          # long enough to still hold the folder
    first = subprocess.Popen([sys.executable, "-m", "scenarios.cli", "run", str(slow), "--out", str(out), "--quiet"],
                             env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        # the first job writes into a temporary sibling, moved into place when complete (issue 28)
        while time.monotonic() < deadline and not list(tmp_path.glob(".Z.*.part/data")):
            time.sleep(0.02)
        assert list(tmp_path.glob(".Z.*.part/data")), "the first job never started writing"
        assert not out.exists()                                   # nothing in place before it is complete
        second = subprocess.run([sys.executable, "-m", "scenarios.cli", "run", str(_scenario(tmp_path, "other")),
                                 "--out", str(out), "--quiet"], env=env, capture_output=True, text=True, timeout=300)
        assert second.returncode == 2, second.stderr
        assert "another ipmc run is writing into this folder" in second.stderr and str(out) in second.stderr
    finally:
        first.communicate(timeout=600)
    assert first.returncode == 0
    report = (out / "report.md").read_text()
    assert "Scenario `slow`" in report and "other" not in report


def test_another_runs_folder_needs_force(tmp_path, capsys):
    out = tmp_path / "Z"
    assert main(["run", str(_scenario(tmp_path, "first")), "--out", str(out), "--quiet"]) == 0
    before = (out / "report.md").read_text()
    assert main(["run", str(_scenario(tmp_path, "second")), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "ipmc run first" in err and "--force" in err
    assert (out / "report.md").read_text() == before                  # untouched
    assert main(["run", str(_scenario(tmp_path, "first")), "--out", str(out), "--quiet"]) == 0   # its own: fine
    assert main(["run", str(_scenario(tmp_path, "second")), "--out", str(out), "--quiet", "--force"]) == 0
    assert "Scenario `second`" in (out / "report.md").read_text()


def test_a_scenario_name_cannot_escape_the_working_directory(tmp_path):
    work = tmp_path / "a" / "b" / "cwd"
    work.mkdir(parents=True)
    sc = _scenario(tmp_path, "x")
    sc.write_text(sc.read_text().replace('name = "x"', 'name = "/../../../escaped"'))
    old = os.getcwd()
    try:
        os.chdir(work)
        assert main(["run", str(sc), "--quiet"]) == 0
    finally:
        os.chdir(old)
    assert [p.name for p in work.iterdir()] == ["ipmc-run-escaped"]
    assert sorted(p.name for p in (tmp_path / "a" / "b").iterdir()) == ["cwd"]
    assert not (tmp_path / "escaped").exists()
