"""The [next_measurement] step gives every record its own noise stream (issue 27 review): the
recommended records' streams come from the SeedSequence entropy ``[next_noise_seed, k, 0, 0, 0]``,
so no two records of a run share one, and none is the stream of an integer seed a user may give to
another run (before: ``next_noise_seed`` and ``next_noise_seed + 1``, integers; then ``[next_noise_seed,
k]``, which numpy gives for the integer ``2**32·k + next_noise_seed`` too)."""

from __future__ import annotations

import numpy as np
import pytest


def _state(seed) -> tuple:
    """What ``default_rng(seed)`` seeds its PCG64 with (numpy's SeedSequence, not the step's code):
    two seeds give one stream exactly when these agree."""
    return tuple(np.random.SeedSequence(seed).generate_state(4, np.uint64).tolist())


def test_no_two_records_share_a_noise_stream(tmp_path, monkeypatch, second_recommended_record):
    """The bundled demo with ``next_noise_seed = noise_seed - 1`` (a value a user may well give) and a
    second recommended record (as in test_next_measurement_two_records): the noise seeds the virtual
    lab receives for records 1-3 give three different streams, and records 2 and 3 none of the
    integer seeds 0-999 or ``2**32·k + next_noise_seed`` (k = 1, 2) gives (any of which a user may give
    as another run's ``noise_seed`` or ``ipmc simulate --seed``).  Before the fix record 3 drew from
    ``next_noise_seed + 1 = noise_seed``: record 1's noise again; with the key ``[next_noise_seed, k]``
    record 2 drew the integer 2**32 + 4's."""
    import scenarios.virtual_lab as vl
    from scenarios.runner import run_scenario
    from scenarios.spec import bundled_scenarios, load_scenario

    real_lab = vl.from_config
    seeds = []

    def lab(model, sweep, noise=None, where=""):
        seeds.append(noise["seed"])
        return real_lab(model, sweep, noise, where)

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
    plain = {_state(s) for s in [*range(1000), *(2**32 * k + 4 for k in (1, 2))]}
    assert not set(states[1:]) & plain, seeds


@pytest.mark.parametrize("root", [0, 5, 2**32 - 1])
def test_no_integer_gives_a_recommended_records_stream(root):
    """The keys of :func:`record_noise_seed` against integers numpy splits into the same leading
    words: ``2**32·k + root`` (two words ``[root, k]``), ``2**64·k + root``, and integers of five words
    (``≥ 2**128``) with the same low words or random high ones — numpy's SeedSequence states, none equal.
    The integer ``2**32·k + root`` does give ``[root, k]``'s state (why the key is five words)."""
    from scenarios.steps_next_measurement import record_noise_seed

    cfg = {"noise_seed": 7, "next_noise_seed": root}
    keys = {k: _state(record_noise_seed(cfg, k)) for k in (1, 2)}
    assert record_noise_seed(cfg, 0) == 7 and len(set(keys.values())) == 2
    rng = np.random.default_rng(root)
    for k, key in keys.items():
        assert _state(2**32 * k + root) == _state([root, k])          # the reachable two-word key
        ints = [root, 2**32 * k + root, 2**64 * k + root, 2**128 + 2**32 * k + root, 2**128 * k + root,
                2**160 + 2**32 * k + root, *(root + 2**32 * k + 2**128 * int(h) for h in rng.integers(1, 2**62, 50))]
        assert key not in {_state(i) for i in ints}, (root, k)


@pytest.mark.parametrize("bad", ["-1", "4294967296", "2.5"])
def test_a_seed_outside_one_word_is_refused_naming_the_key(tmp_path, capsys, bad):
    """``next_noise_seed`` outside [0, 2**32) (one word, so a record's key is always ``[next_noise_seed, k,
    0, 0, 0]``) or not an integer: the CLI exits 2 naming the key and the value, no traceback."""
    from scenarios.cli import main
    from scenarios.spec import bundled_scenarios

    demo = [p for p in bundled_scenarios() if p.stem == "next_measurement_demo"][0].read_text(encoding="utf-8")
    path = tmp_path / "bad.toml"
    path.write_text(demo.replace("noise_seed = 5\n", f"noise_seed = 5\nnext_noise_seed = {bad}\n"), encoding="utf-8")
    assert main(["run", str(path), "--quick", "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "next_noise_seed" in err and bad in err and "Traceback" not in err
