"""Saved models: files of schema version 1 (zpk zero sections s̃² + c1 s̃ + c0) stay readable.

The fixtures in tests/surrogate/data/ were written by ``RationalModel.to_json`` at commit 15edda3,
before the zpk zero sections became 1 + β1 s̃ + β2 s̃² (schema version 2).  Oracles: the schema-1
formula written out here from the file's numbers, and responses printed by 15edda3's code when
it saved the files.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from surrogate import RationalModel, Scaling, Structure, load
from surrogate.models import SCHEMA_VERSION

DATA = Path(__file__).parent / "data"
PRINTED_AT_30C = {  # frequency_response([0.1, 1.0, 10.0] Hz, 30 °C) printed by 15edda3 on saving
    "zpk_schema1_2z3p_quadratic.json": [0.71242067 - 0.25925519j, -1.12716128 - 0.47995468j,
                                        0.35186689 - 0.86770226j],
    "zpk_schema1_3z4p_linear.json": [-0.18940704 + 0.02948896j, 0.06702703 + 0.31783784j,
                                     0.0130014 - 0.03797249j],
}


def _schema1_response(doc, f_hz, temp_c):
    """H from a schema-1 zpk document, written out independently of the package."""
    st, sc = doc["structure"], doc["scaling"]
    nc = st["degree"] + 1
    vals = dict(zip(doc["params"]["names"], doc["params"]["values"]))
    tau = (temp_c - sc["temperature_center_c"]) / sc["temperature_scale_c"]

    def slot(name):
        if nc == 1:
            return vals[name]
        return sum(vals[f"{name}:t{q}"] * tau ** q for q in range(nc))

    s = 2j * np.pi * np.asarray(f_hz) / sc["omega_ref_rad_s"]
    m, n = st["n_zeros"], st["n_poles"]
    num = slot("k") * np.ones_like(s)
    for k in range(m // 2):
        num = num * (s * s + slot(f"zc1_{k}") * s + slot(f"zc0_{k}"))
    if m % 2:
        num = num * (s + slot("ze"))
    den = np.ones_like(s)
    for k in range(n // 2):
        den = den * (s * s + np.exp(slot(f"log_a1_{k}")) * s + np.exp(slot(f"log_a0_{k}")))
    if n % 2:
        den = den * (s + np.exp(slot("log_c")))
    return sc["gain_ref"] * num / den


@pytest.mark.parametrize("name", sorted(PRINTED_AT_30C))
def test_schema_1_zpk_files_read_as_they_were_saved(name):
    path = DATA / name
    doc = json.loads(path.read_text())
    assert doc["schema_version"] == 1 and "zero_sections" not in doc["structure"]
    model = load(path)
    assert model.structure.form == "zpk" and model.structure.zero_sections == "monic"
    np.testing.assert_allclose(model.frequency_response([0.1, 1.0, 10.0], 30.0), PRINTED_AT_30C[name],
                               rtol=0, atol=1e-8)    # printed to 8 decimals
    lo, hi = doc["temperature_range_c"]
    f = np.geomspace(0.05, 50.0, 37)
    for t in np.linspace(lo, hi, 5):
        np.testing.assert_allclose(model.frequency_response(f, t), _schema1_response(doc, f, t), rtol=1e-12)
        # zeros, poles and coefficients agree with the response they describe
        num, den = model.coefficients(t)
        assert np.allclose(np.polyval(num, 2j * np.pi * f) / np.polyval(den, 2j * np.pi * f),
                           _schema1_response(doc, f, t), rtol=1e-9)
        assert model.zeros(t).size == doc["structure"]["n_zeros"]
        assert np.max(np.abs(np.polyval(num, model.zeros(t)))) <= 1e-9 * np.max(np.abs(num)) * max(
            1.0, np.max(np.abs(model.zeros(t)))) ** num.size


def test_a_schema_1_model_saved_again_is_schema_2_and_unchanged(tmp_path):
    model = load(DATA / "zpk_schema1_3z4p_linear.json")
    model.to_json(tmp_path / "again.json")
    doc = json.loads((tmp_path / "again.json").read_text())
    assert doc["schema_version"] == SCHEMA_VERSION == 2
    assert doc["structure"]["zero_sections"] == "monic"
    back = load(tmp_path / "again.json")
    f = np.geomspace(0.1, 10.0, 9)
    np.testing.assert_array_equal(back.frequency_response(f, 20.0), model.frequency_response(f, 20.0))


def test_new_zpk_models_are_saved_with_unit_zero_sections(tmp_path):
    st = Structure("zpk", 3, 3, 1)
    assert st.zero_sections == "unit" and st.param_names()[2:8] == [
        "zb1_0:t0", "zb1_0:t1", "zb2_0:t0", "zb2_0:t1", "zb:t0", "zb:t1"]
    theta = np.array([2.0, 0.1, -0.3, 0.05, 0.2, 0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.2, 0.1])   # zb = 0: zero at ∞
    model = RationalModel(st, theta, Scaling(1.0, 1.0, 0.0, 1.0), (-1.0, 1.0))
    model.to_json(tmp_path / "m.json")
    doc = json.loads((tmp_path / "m.json").read_text())
    assert doc["schema_version"] == 2 and doc["structure"]["zero_sections"] == "unit"
    # N = 2 (1 - 0.3 s + 0.2 s²) at τ = 0 (the real zero is at infinity: left out of the zeros)
    z = load(tmp_path / "m.json").zeros(0.0)
    np.testing.assert_allclose(np.sort_complex(z), np.sort_complex(np.roots([0.2, -0.3, 1.0])), rtol=1e-12)
    s = 1j * np.array([0.3, 3.0])
    expect = 2.0 * (1 - 0.3 * s + 0.2 * s * s) / ((s * s + np.exp(0.1) * s + 1.0) * (s + np.exp(0.2)))
    np.testing.assert_allclose(model.frequency_response(np.abs(s) / (2 * np.pi), 0.0), expect, rtol=1e-12)


@pytest.mark.parametrize("edit, match", [
    (lambda d: d.update(schema_version=3), "unsupported schema_version 3"),
    (lambda d: d.update(schema_version=True), "unsupported schema_version True"),
    (lambda d: d["structure"].update(zero_sections="monic"), "not part of schema_version 1"),
    (lambda d: d.update(schema_version=2), "parameter names do not match"),   # v1 names, v2 default sections
    (lambda d: d["structure"].update(zero_sections="cubic") or d.update(schema_version=2),
     "key 'structure' or 'scaling': zero_sections must be one of"),
])
def test_bad_schema_1_and_2_documents_are_refused_naming_the_key(tmp_path, edit, match):
    doc = json.loads((DATA / "zpk_schema1_3z4p_linear.json").read_text())
    edit(doc)
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=match):
        load(p)
