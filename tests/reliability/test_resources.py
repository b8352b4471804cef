"""Issue 28: every count or size that drives an allocation is bounded before anything is
allocated (exit 2 naming the option and the largest value this machine holds), and physical
inputs outside any plausible range are refused before numerical work."""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import pytest

from scenarios.cli import main

sys.path.insert(0, str(Path(__file__).parent))
import fuzzcases  # noqa: E402
from _faults import env  # noqa: E402


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    d = tmp_path_factory.mktemp("res")
    return fuzzcases.valid_sweep(d, "sweep.csv", temps=(20.0, 40.0), points=10)


def _largest(err: str) -> int:
    return int(err.split("at most ", 1)[1].split()[0])


@pytest.mark.parametrize("n", ["1000000000000", "9223372036854775808", str(10**30)])
def test_huge_null_draws_are_refused_naming_the_option_and_the_limit(sweep, tmp_path, capsys, n):
    t0 = time.perf_counter()
    assert main(["diagnose", "--data", str(sweep), "--set", "seed002_table3", "--null-draws", n,
                 "--out", str(tmp_path / "d"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"--null-draws {n}" in err and "on this machine" in err
    # the largest value stated is one this machine can hold: a (2·lines × draws) float64 array of
    # that size fits twice over in what is available (independent arithmetic, not the code's)
    from scenarios.commands._common import available_memory

    assert 2 * (2 * 20) * 8 * _largest(err) <= available_memory()
    assert time.perf_counter() - t0 < 30 and not (tmp_path / "d").exists()


def test_huge_null_draws_in_the_experiment_file_name_the_key(sweep, tmp_path, capsys):
    toml = tmp_path / "e.toml"
    toml.write_text(f'data = "{sweep}"\nset = "seed002_table3"\nnull_draws = 1000000000000\nout = "{tmp_path / "d"}"\n')
    assert main(["diagnose", str(toml), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "null_draws" in err and str(toml) in err and "at most" in err


def test_the_bound_follows_the_memory_this_process_may_use(sweep, tmp_path):
    """Under an address-space limit of 3 GiB the largest value shrinks accordingly (checked in a
    subprocess, so the limit does not stay with the test process)."""
    code = ("import resource, sys; lim = 3 << 30; resource.setrlimit(resource.RLIMIT_AS, (lim, lim)); "
            "from scenarios.cli import main; sys.exit(main(sys.argv[1:]))")
    p = subprocess.run([sys.executable, "-c", code, "diagnose", "--data", str(sweep), "--set", "seed002_table3",
                        "--null-draws", "100000000", "--out", str(tmp_path / "d"), "--quiet"], env=env(),
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 2, p.stderr[-800:]
    assert "Traceback" not in p.stderr and "MemoryError" not in p.stderr
    assert _largest(p.stderr) * 8 * (4 * 20 + 16) <= (3 << 30) // 2


def test_a_study_larger_than_memory_is_refused_before_it_runs(tmp_path):
    text = (Path(__file__).resolve().parents[2] / "scenarios" / "studies" / "actuator_mc.toml").read_text()
    (tmp_path / "s.toml").write_text(text.replace("samples = 200", "samples = 100000").replace("points = 40",
                                                                                               "points = 100"))
    code = ("import resource, sys; lim = 2 << 30; resource.setrlimit(resource.RLIMIT_AS, (lim, lim)); "
            "from scenarios.cli import main; sys.exit(main(sys.argv[1:]))")
    p = subprocess.run([sys.executable, "-c", code, "study", str(tmp_path / "s.toml"), "--out",
                        str(tmp_path / "t.csv"), "--quiet", "--serial"], env=env(), capture_output=True, text=True,
                       timeout=300)
    assert p.returncode == 2, p.stderr[-800:]
    assert "samples × temperatures_c × frequencies 30000000" in p.stderr and "at most" in p.stderr
    assert not (tmp_path / "t.csv").exists()


@pytest.mark.parametrize("argv,option", [
    (["excite", "multisine", "--fs", "1000", "--period", "200000", "--count", "5", "--fmin", "1", "--fmax", "10"],
     "--period × --fs"),
    (["excite", "chirp", "--f0", "1", "--f1", "10", "--sweep-s", "1e12", "--fs", "1000"], "--sweep-s × --fs"),
])
def test_generated_records_are_bounded(tmp_path, capsys, argv, option):
    lim = resource.getrlimit(resource.RLIMIT_AS)
    t0 = time.perf_counter()
    assert main([*argv, "--out", str(tmp_path / "x.npz"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert option in err and "at most" in err
    assert time.perf_counter() - t0 < 20 and resource.getrlimit(resource.RLIMIT_AS) == lim


@pytest.mark.parametrize("value", ["1e300", "-1e300", "1e-300"])
def test_a_length_outside_any_physical_range_is_refused_before_numerical_work(tmp_path, capsys, value):
    assert main(["simulate", "--param", f"L={value}", "--out", str(tmp_path / "s.csv"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "L=" in err.replace(" ", "") and ("physical range" in err or "must be > 0" in err)
    assert "Traceback" not in err
    assert not (tmp_path / "s.csv").exists()


def test_a_parameter_file_with_an_absurd_length_is_refused(tmp_path, capsys):
    from physmodel import get_parameter_set, save_parameter_set

    path = save_parameter_set(get_parameter_set("seed002_table3"), tmp_path / "p.json")
    d = json.loads(path.read_text())
    d["parameters"]["L"] = 1e300
    path.write_text(json.dumps(d))
    for argv in (["sweep", "--params-json", str(path), "--points", "5", "--out", str(tmp_path / "s.csv")],
                 ["simulate", "--params-json", str(path), "--out", str(tmp_path / "t.csv")]):
        assert main([*argv, "--quiet"]) == 2
        err = capsys.readouterr().err
        assert str(path) in err and "L = 1e+300 m" in err


def test_calibrate_refuses_an_absurd_start_before_fitting(sweep, tmp_path, capsys):
    assert main(["calibrate", str(sweep), "--set", "seed002_table3", "--param", "W=1e6", "--free", "d",
                 "--out", str(tmp_path / "c"), "--quiet"]) == 2
    assert "W = 1e+06 m" in capsys.readouterr().err


def test_every_shipped_parameter_set_is_physical():
    from physmodel import get_parameter_set
    from physmodel.parameter_sets import available_parameter_sets
    from physmodel.plausible import check_physical

    for name in available_parameter_sets():
        check_physical(get_parameter_set(name))


def test_a_scenario_or_study_with_an_absurd_length_is_refused(tmp_path, capsys):
    from physmodel import get_parameter_set, save_parameter_set

    doc = fuzzcases._deep(fuzzcases.MINI_SCENARIO)
    doc["model"]["params"] = {"L": 1e300}
    doc.pop("surrogate")
    assert main(["run", str(fuzzcases.write_scenario(tmp_path, doc)), "--out", str(tmp_path / "r"), "--quiet"]) == 2
    assert "params.L = 1e+300" in capsys.readouterr().err and not (tmp_path / "r").exists()
    path = save_parameter_set(get_parameter_set("seed001_actuator_dev"), tmp_path / "p.json")
    d = json.loads(path.read_text())
    d["parameters"]["L"] = 1e300
    path.write_text(json.dumps(d))
    text = (Path(__file__).resolve().parents[2] / "scenarios" / "studies" / "actuator_mc.toml").read_text()
    (tmp_path / "s.toml").write_text(text.replace('set = "seed001_actuator_dev"', f'set = "{path}"'))
    assert main(["study", str(tmp_path / "s.toml"), "--out", str(tmp_path / "t.csv"), "--quiet", "--serial"]) == 2
    assert "L = 1e+300 m" in capsys.readouterr().err
