"""The surrogate's own verdict travels: ``ipmc fit`` records in model.json whether the rational
model fits the sweep it was fitted to, and ``ipmc feedforward``/``ipmc invert`` say it on stderr
and in the files they write, and exit 3 unless ``--accept-misfit`` (as for a physics misfit).

The sweep is written here from a plant in closed form (two poles and a lag the one-pole fit cannot
represent), with 0.05 dB / 0.3° noise: a one-pole surrogate cannot fit it, a two-pole one can."""

from __future__ import annotations

import json

import numpy as np
import pytest

from physmodel.data.files import write_sweep
from physmodel.data.sweep import FrequencySweep
from scenarios.cli import main

F = np.logspace(-1, 1.5, 40)
T = (25.0, 30.0, 35.0)


def _plant(f):
    s = 2j * np.pi * f
    wn, z = 2 * np.pi * 8.0, 0.2
    return 0.5 * wn**2 / (s**2 + 2 * z * wn * s + wn**2)       # mm/V


@pytest.fixture(scope="module")
def fits(tmp_path_factory):
    root = tmp_path_factory.mktemp("sfit")
    rng = np.random.default_rng(3)
    f = np.tile(F, len(T))
    temps = np.repeat(T, F.size)
    sdb, sdeg = 0.05, 0.3
    H = _plant(f) * 10 ** (rng.normal(0, sdb, f.size) / 20) * np.exp(1j * np.radians(rng.normal(0, sdeg, f.size)))
    write_sweep(FrequencySweep(temps, f, H, np.full(f.size, sdb), np.full(f.size, sdeg),
                               "voltage", "V", "tip_displacement", "mm"), root / "sweep.csv")
    rc_bad = main(["fit", str(root / "sweep.csv"), "--zeros", "0", "--poles", "1", "--out", str(root / "bad"),
                   "--quiet"])
    rc_good = main(["fit", str(root / "sweep.csv"), "--zeros", "0", "--poles", "2", "--out", str(root / "good"),
                    "--quiet"])
    return root, rc_bad, rc_good


def test_fit_records_its_verdict_in_model_json(fits, capsys):
    root, rc_bad, rc_good = fits
    assert rc_bad == 3 and rc_good == 0
    bad = json.loads((root / "bad" / "model.json").read_text())["info"]["adequacy"]
    good = json.loads((root / "good" / "model.json").read_text())["info"]["adequacy"]
    assert bad["adequate"] is False and "does not fit" in bad["reason"] and bad["accepted"] is False
    assert good["adequate"] is True


def test_feedforward_says_the_surrogate_misfit_and_exits_3(fits, capsys):
    root, _, _ = fits
    ff = ["--temperature", "30", "--reference", "sine", "--amplitude", "0.1", "--frequency", "1", "--fs", "1000",
          "--quiet", "--improper", "filter", "--filter-bandwidth", "2000"]
    capsys.readouterr()
    rc = main(["feedforward", str(root / "bad" / "model.json"), *ff, "--out", str(root / "ff_bad")])
    err = capsys.readouterr().err
    assert rc == 3 and "the surrogate does not fit the sweep it was fitted to" in err
    head = (root / "ff_bad" / "voltage.csv").read_text()
    assert "# upstream_misfit: the surrogate does not fit" in head
    rep = json.loads((root / "ff_bad" / "report.json").read_text())
    assert any("surrogate does not fit" in u for u in rep["upstream_misfit"]) and rep["exit_code"] == 3
    rc = main(["feedforward", str(root / "bad" / "model.json"), *ff, "--out", str(root / "ff_acc"),
               "--accept-misfit"])
    assert rc == 0 and "# upstream_misfit: the surrogate does not fit" in (root / "ff_acc" / "voltage.csv").read_text()
    rc = main(["feedforward", str(root / "good" / "model.json"), *ff, "--out", str(root / "ff_good")])
    assert rc == 0 and "upstream_misfit" not in (root / "ff_good" / "voltage.csv").read_text()


def test_invert_says_the_surrogate_misfit_and_exits_3(fits, capsys):
    root, _, _ = fits
    t = np.arange(2000) / 1000.0
    y = 0.1 * np.sin(2 * np.pi * 1.0 * t) * np.sin(np.pi * t / t[-1]) ** 2
    np.savetxt(root / "tip.csv", np.column_stack([t, y]), delimiter=",", header="time_s,tip_mm", comments="")
    args = ["--temperature", "30", "--improper", "differentiate", "--quiet"]
    capsys.readouterr()
    rc = main(["invert", str(root / "tip.csv"), "--surrogate", str(root / "bad" / "model.json"), *args,
               "-o", str(root / "v_bad.csv")])
    err = capsys.readouterr().err
    assert rc == 3 and "surrogate_misfit: the surrogate does not fit" in err
    assert "# surrogate_misfit: the surrogate does not fit" in (root / "v_bad.csv").read_text()
    rc = main(["invert", str(root / "tip.csv"), "--surrogate", str(root / "bad" / "model.json"), *args,
               "--accept-misfit", "-o", str(root / "v_acc.csv")])
    assert rc == 0
    rc = main(["invert", str(root / "tip.csv"), "--surrogate", str(root / "good" / "model.json"), *args,
               "-o", str(root / "v_good.csv")])
    assert rc == 0 and "surrogate_misfit" not in (root / "v_good.csv").read_text()
