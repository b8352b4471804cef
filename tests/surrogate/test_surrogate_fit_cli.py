"""Persistence (versioned JSON, no pickle), python-control interchange and the `fit` CLI."""

import argparse
import json

import numpy as np
import pytest
from surrogate_fixtures import noisy_sweep

import surrogate
from scenarios.commands.fit import add_parser, read_csv, run
from surrogate import RationalFit, ScheduledFit, load


@pytest.fixture(scope="module")
def fitted(synthetic_sweep):
    f, t, h, sm, sp = synthetic_sweep
    return ScheduledFit("zpk", 2, 3, 2).fit(f, t, h, sm, sp)


def test_json_round_trip(fitted, tmp_path):
    path = tmp_path / "m.json"
    fitted.model.to_json(path)
    doc = json.loads(path.read_text())
    assert doc["schema"] == "ipmc.surrogate.rational_model" and doc["schema_version"] == 2
    assert doc["info"]["data_fingerprint"] == fitted.data_fingerprint
    assert doc["info"]["settings"]["form"] == "zpk" and doc["info"]["settings"]["degree"] == 2
    back = load(path)
    f = np.geomspace(0.1, 30, 17)
    for t in (19.0, 33.3, 55.0):
        np.testing.assert_array_equal(back.frequency_response(f, t), fitted.model.frequency_response(f, t))
    np.testing.assert_array_equal(back.covariance, fitted.model.covariance)
    assert back.temperature_range_c == (19.0, 55.0)
    assert [r["name"] for r in back.parameter_table()] == fitted.param_names


def test_load_rejects_other_schemas(tmp_path, fitted):
    doc = fitted.model.to_dict()
    doc["schema_version"] = 99
    p = tmp_path / "future.json"
    p.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="unsupported schema_version 99"):
        load(p)
    p.write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        load(p)


def test_fingerprint_tracks_the_data(synthetic_sweep):
    f, t, h, sm, sp = synthetic_sweep
    a = surrogate.FrequencyData(f, t, h, sm, sp).fingerprint()
    h2 = h.copy()
    h2[5] *= 1 + 1e-12
    assert a == surrogate.FrequencyData(f, t, h, sm, sp).fingerprint()
    assert a != surrogate.FrequencyData(f, t, h2, sm, sp).fingerprint()
    assert a.startswith("sha256:") and len(a) == 7 + 64


def test_transfer_function_matches_frequency_response(fitted):
    f = np.geomspace(0.1, 30, 25)
    for t in (19.0, 40.0):
        tf = fitted.model.at(t)
        h_tf = tf(2j * np.pi * f)
        np.testing.assert_allclose(np.asarray(h_tf).ravel(), fitted.model.frequency_response(f, t), rtol=1e-9)
        np.testing.assert_allclose(np.sort_complex(tf.poles()), np.sort_complex(fitted.model.poles(t)), rtol=1e-7)


def _write_csv(path, f, t, h, sm=None, sp=None, header_extra=""):
    cols = "temperature_c,frequency_hz,magnitude_db,phase_deg" + (",magnitude_std_db,phase_std_deg" if sm is not None else "")
    lines = ["# input: voltage [V]", "# output: tip_displacement [mm]", "# source: test", header_extra, cols]
    for i in range(f.size):
        row = [t[i], f[i], 20 * np.log10(abs(h[i])), np.degrees(np.angle(h[i]))]
        if sm is not None:
            row += [sm[i], sp[i]]
        lines.append(",".join(repr(float(v)) for v in row))
    path.write_text("\n".join(lines) + "\n")


def _args(argv):
    parser = argparse.ArgumentParser(prog="ipmc")
    add_parser(parser.add_subparsers(dest="command"))
    return parser.parse_args(argv)


def test_cli_fit_writes_model_report_and_figures(tmp_path, true_model):
    f, t, h, sm, sp = noisy_sweep(true_model, [19.0, 25.0, 31.0, 37.0, 43.0, 49.0, 55.0], np.geomspace(0.1, 30, 30))
    csv = tmp_path / "sweep.csv"
    _write_csv(csv, f, t, h, sm, sp)
    data = read_csv(csv)
    assert data.input_unit == "V" and data.output_name == "tip_displacement" and data.has_uncertainty
    np.testing.assert_allclose(data.response, h, rtol=1e-12)
    out = tmp_path / "out"
    args = _args(["fit", str(csv), "--zeros", "2", "--poles", "3", "--degree", "2", "--exclude", "37", "--out", str(out)])
    assert args.func is run
    assert run(args) == 0
    model = load(out / "model.json")
    assert model.info["temperatures_c"] == [19.0, 25.0, 31.0, 43.0, 49.0, 55.0]
    report = (out / "report.md").read_text()
    assert "| 37 | held out |" in report and "converged" in report
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert "poles_zeros_vs_temperature.png" in pngs and "bode_37C.png" in pngs and len(pngs) == 8
    assert not list(out.glob(".*.tmp"))
    fq = np.geomspace(0.1, 30, 40)
    err = surrogate.relative_rms_error(model.frequency_response(fq, 37.0), true_model.frequency_response(fq, 37.0))
    assert err < 0.02


def test_cli_bad_input_and_non_convergence_exit_codes(tmp_path, true_model, capsys):
    f, t, h, sm, sp = noisy_sweep(true_model, [19.0, 37.0, 55.0], np.geomspace(0.1, 30, 20))
    bad = tmp_path / "bad.csv"
    _write_csv(bad, f, t, h)
    bad.write_text(bad.read_text().replace(repr(float(f[3])), "nan", 1))
    assert run(_args(["fit", str(bad), "--out", str(tmp_path / "o1")])) == 2
    assert "frequency_hz is 'nan'; expected a finite number" in capsys.readouterr().err
    missing = tmp_path / "missing.csv"
    missing.write_text("# input: voltage [V]\ntemperature_c,frequency_hz,magnitude_db\n25,1,0\n")
    assert run(_args(["fit", str(missing), "--out", str(tmp_path / "o2")])) == 2
    assert "missing column(s) ['phase_deg']" in capsys.readouterr().err
    assert run(_args(["fit", str(tmp_path / "nope.csv"), "--out", str(tmp_path / "o3")])) == 2
    good = tmp_path / "good.csv"
    _write_csv(good, f, t, h, sm, sp)
    # degree 1 through 3 temperatures: one iteration cannot converge (at degree 2 the coefficient
    # form's schedule interpolates the 3 temperatures, and the joint fit started from it converges
    # in one iteration)
    assert run(_args(["fit", str(good), "--zeros", "2", "--poles", "3", "--degree", "1", "--max-iter", "1",
                      "--out", str(tmp_path / "o4")])) == 3
    assert "did not converge" in capsys.readouterr().err
    assert not (tmp_path / "o4" / "model.json").exists()


def test_single_temperature_model_round_trip(tmp_path):
    f = np.geomspace(1, 100, 30)
    h = 5.0 / (1 + 1j * f / 20.0) / (1 + 1j * f / 70.0)
    res = RationalFit(0, 2).fit(f, 25.0, h)
    res.model.to_json(tmp_path / "one.json")
    back = load(tmp_path / "one.json")
    np.testing.assert_allclose(back.frequency_response(f), h, rtol=1e-8)
    assert back.frequency_response(f, 25.0).shape == f.shape
    with pytest.raises(ValueError, match="outside the model's validity range"):
        back.frequency_response(f, 30.0)
