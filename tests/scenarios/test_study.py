"""``ipmc study``: the same seed gives bit-identical tidy tables in this process, on local
processes and on a Dask LocalCluster; rows agree with direct model evaluations; draws follow
their distributions; bad specs exit 2."""

from __future__ import annotations

import numpy as np
import pytest

import physmodel
from scenarios.cli import main
from scenarios.study import StudyError, load_study, parse_study, run_study

SPEC = {"study": {
    "name": "t", "kind": "actuator", "set": "seed001_actuator_dev", "method": "monte_carlo", "samples": 23,
    "seed": 5, "temperatures_c": [20.0, 50.0], "fmin_hz": 0.5, "fmax_hz": 5.0, "points": 7, "chunk_size": 4,
    "noise": {"kind": "magphase", "sigma_db": 0.2, "sigma_deg": 1.0},
    "parameters": {"d": {"distribution": "lognormal", "median": 4e-11, "sigma": 0.3},
                   "E": {"distribution": "normal", "mean": 3e8, "std": 3e7},
                   "r1_sheet": {"distribution": "uniform", "low": 5.0, "high": 20.0}}}}


@pytest.fixture(scope="module")
def serial():
    return run_study(parse_study(SPEC), backend="serial")


def test_table_is_tidy_and_rows_match_the_model(serial):
    c = serial.columns
    assert list(c) == ["sample", "d", "E", "r1_sheet", "temperature_c", "frequency_hz", "magnitude_db", "phase_deg",
                       "real", "imag"]
    assert serial.n_rows == 23 * 2 * 7
    noiseless = run_study(parse_study({"study": {k: v for k, v in SPEC["study"].items() if k != "noise"}}),
                          backend="serial").columns
    i = 17
    row = noiseless["sample"] == i
    p = physmodel.get_parameter_set("seed001_actuator_dev", d=noiseless["d"][row][0], E=noiseless["E"][row][0],
                                    r1_sheet=noiseless["r1_sheet"][row][0])
    f = np.geomspace(0.5, 5.0, 7)
    M = physmodel.ActuatorModel(p).frequency_response(f, [20.0, 50.0])["M"][0] * 1e3   # mm/V
    np.testing.assert_allclose(noiseless["real"][row] + 1j * noiseless["imag"][row], M.ravel(), rtol=1e-12)
    # noise is per sample, seeded: the noisy table differs from the exact one by ~0.2 dB
    d_db = c["magnitude_db"] - noiseless["magnitude_db"]
    assert 0.1 < np.std(d_db) < 0.3


def test_draws_follow_their_distributions():
    big = parse_study({"study": {**SPEC["study"], "samples": 4000, "points": 2, "temperatures_c": [25.0],
                                 "chunk_size": 4000}})
    c = run_study(big, backend="serial").columns
    first = c["sample"] != np.roll(c["sample"], 1)
    d, E, r1 = c["d"][first], c["E"][first], c["r1_sheet"][first]
    se = 1 / np.sqrt(d.size)
    assert abs(np.median(np.log(d / 4e-11))) < 4 * 0.3 * 1.25 * se
    assert abs(np.std(np.log(d)) / 0.3 - 1) < 0.05
    assert abs(np.mean(E) - 3e8) < 4 * 3e7 * se
    assert r1.min() >= 5.0 and r1.max() <= 20.0 and abs(np.mean(r1) - 12.5) < 4 * 15 / np.sqrt(12) * se


def test_grid_study_enumerates_the_product():
    g = parse_study({"study": {"kind": "sensor", "set": "seed000_sensor_dev", "method": "grid", "seed": 0,
                               "temperatures_c": [25.0], "frequencies_hz": [10.0, 20.0],
                               "parameters": {"d": {"values": [3e-11, 4e-11, 5e-11]}, "xi": {"values": [0.05, 0.1]}}}})
    c = run_study(g, backend="serial").columns
    assert g["samples"] == 6
    pairs = {(a, b) for a, b in zip(c["d"], c["xi"])}
    assert pairs == {(a, b) for a in (3e-11, 4e-11, 5e-11) for b in (0.05, 0.1)}


def test_local_processes_give_the_identical_table(serial):
    assert run_study(parse_study(SPEC), workers=2).equals(serial)
    # chunking does not matter either; another seed does
    assert run_study(parse_study({"study": {**SPEC["study"], "chunk_size": 5}}), workers=2).equals(serial)
    assert not run_study(parse_study({"study": {**SPEC["study"], "seed": 6}}), backend="serial").equals(serial)


@pytest.mark.parametrize("processes", [False, pytest.param(True, marks=pytest.mark.slow)])     # worker processes: ~5 s
def test_dask_local_cluster_gives_the_identical_table(serial, processes):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=processes,
                                  dashboard_address=None) as cluster:
        table = run_study(parse_study(SPEC), scheduler=cluster.scheduler_address)
    assert table.backend == "dask"
    assert table.equals(serial)


def test_cli_writes_csv_and_npz(tmp_path, serial):
    spec = tmp_path / "s.toml"
    spec.write_text(_to_toml(SPEC))
    assert main(["study", str(spec), "--out", str(tmp_path / "t.npz"), "--quiet", "--workers", "2"]) == 0
    z = np.load(tmp_path / "t.npz")
    for k, v in serial.columns.items():
        np.testing.assert_array_equal(z[k], v)
    assert main(["study", str(spec), "--out", str(tmp_path / "t.csv"), "--quiet", "--serial"]) == 0
    import csv

    lines = [ln for ln in (tmp_path / "t.csv").read_text().splitlines() if not ln.startswith("#")]
    rows = list(csv.DictReader(lines))
    assert list(rows[0]) == list(serial.columns)
    np.testing.assert_array_equal([float(r["magnitude_db"]) for r in rows], serial.columns["magnitude_db"])
    np.testing.assert_array_equal([int(r["sample"]) for r in rows], serial.columns["sample"])


def _to_toml(spec):
    s = spec["study"]
    lines = ["[study]"]
    for k, v in s.items():
        if not isinstance(v, dict):
            lines.append(f"{k} = {v!r}".replace("'", '"'))
    lines += ["[study.noise]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in s["noise"].items()]
    for name, p in s["parameters"].items():
        lines += [f"[study.parameters.{name}]"] + [f"{k} = {v!r}".replace("'", '"') for k, v in p.items()]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("edit,needle", [
    ({"samplez": 3}, "unknown key 'samplez'"),
    ({"parameters": {"width": {"distribution": "uniform", "low": 1, "high": 2}}}, "not a numeric IPMCParameters field"),
    ({"parameters": {"d": {"distribution": "beta", "a": 1}}}, "distribution must be one of"),
    ({"parameters": {"d": {"distribution": "uniform", "low": 2.0, "high": 1.0}}}, "invalid uniform"),
    ({"samples": 0}, "samples must be a positive integer"),
    ({"set": "nope"}, "unknown parameter set"),
])
def test_bad_specs_are_rejected(edit, needle):
    with pytest.raises(ValueError) as e:
        parse_study({"study": {**SPEC["study"], **edit}})
    assert needle in str(e.value)


def test_bad_spec_exit_code_2(tmp_path, capsys):
    p = tmp_path / "s.toml"
    p.write_text('[study]\nkind = "actuator"\n')
    assert main(["study", str(p), "--out", str(tmp_path / "t.csv")]) == 2
    assert "missing required key" in capsys.readouterr().err
    assert not (tmp_path / "t.csv").exists()


def test_bundled_study_loads():
    from pathlib import Path

    import scenarios

    spec = load_study(Path(scenarios.__file__).parent / "studies" / "actuator_mc.toml")
    assert spec["samples"] == 200 and StudyError
