"""The [next_measurement] step gives every record its own noise stream (issue 27 review): the
recommended records' streams come from the SeedSequence entropy ``[next_noise_seed, k]``, so no
two records of a run share one, and none is the stream of an integer seed a user may give to
another run (before: ``next_noise_seed`` and ``next_noise_seed + 1``, integers)."""

from __future__ import annotations

import numpy as np
import pytest


def _state(seed) -> tuple:
    """What ``default_rng(seed)`` seeds its PCG64 with (numpy's SeedSequence, not the step's code):
    two seeds give one stream exactly when these agree."""
    return tuple(np.random.SeedSequence(seed).generate_state(4, np.uint64).tolist())


def test_no_two_records_share_a_noise_stream(tmp_path, monkeypatch):
    """The bundled demo with ``next_noise_seed = noise_seed - 1`` (a value a user may well give) and a
    second recommended record (as in test_next_measurement_two_records): the noise seeds the virtual
    lab receives for records 1-3 give three different streams, and records 2 and 3 none of the
    integer seeds 0-999 gives (any of which a user may give as another run's ``noise_seed``).  Before
    the fix record 3 drew from ``next_noise_seed + 1 = noise_seed``: record 1's noise again."""
    from dataclasses import replace

    import scenarios.virtual_lab as vl
    from physmodel.estimation.diagnosis import Diagnosis
    from scenarios.runner import run_scenario
    from scenarios.spec import bundled_scenarios, load_scenario

    real_nm, real_lab = Diagnosis.recommend_next_measurement, vl.from_config
    seeds = []

    def with_second(self, **kw):
        nm = real_nm(self, **kw)
        r = nm.recommended
        f = np.arange(1.0, 10.0)
        nm.also = [replace(r, band_hz=(1.0, 9.0), temperatures_c=(35.0,), level=1.0, n_lines=f.size, frequencies_hz=f,
                           line_temperatures_c=np.full(f.size, 35.0), line_frequencies_hz=f)]
        nm.together = {"separation": r.separation, "separation_by_pair": dict(r.separation_by_pair),
                       "linearised_only": True}
        return nm

    def lab(model, sweep, noise=None, where=""):
        seeds.append(noise["seed"])
        return real_lab(model, sweep, noise, where)

    monkeypatch.setattr(Diagnosis, "recommend_next_measurement", with_second)
    monkeypatch.setattr(vl, "from_config", lab)
    demo = [p for p in bundled_scenarios() if p.stem == "next_measurement_demo"][0].read_text(encoding="utf-8")
    assert "noise_seed = 5\n" in demo
    path = tmp_path / "streams.toml"
    path.write_text(demo.replace("noise_seed = 5\n", "noise_seed = 5\nnext_noise_seed = 4\n"), encoding="utf-8")
    run_scenario(load_scenario(path, quick=True), tmp_path / "run", quiet=True)
    assert len(seeds) == 3
    states = [_state(s) for s in seeds]
    assert states[0] == _state(5)                                   # the first record: noise_seed's stream
    assert len(set(states)) == 3, seeds
    plain = {_state(s) for s in range(1000)}
    assert not set(states[1:]) & plain, seeds


@pytest.mark.parametrize("bad", ["-1", "4294967296", "2.5"])
def test_a_seed_outside_one_word_is_refused_naming_the_key(tmp_path, capsys, bad):
    """``next_noise_seed`` outside [0, 2**32) (the streams are distinct for one-word seeds only) or not
    an integer: the CLI exits 2 naming the key and the value, no traceback."""
    from scenarios.cli import main
    from scenarios.spec import bundled_scenarios

    demo = [p for p in bundled_scenarios() if p.stem == "next_measurement_demo"][0].read_text(encoding="utf-8")
    path = tmp_path / "bad.toml"
    path.write_text(demo.replace("noise_seed = 5\n", f"noise_seed = 5\nnext_noise_seed = {bad}\n"), encoding="utf-8")
    assert main(["run", str(path), "--quick", "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "next_noise_seed" in err and bad in err and "Traceback" not in err
