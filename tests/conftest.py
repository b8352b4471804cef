"""Suite-wide settings: hypothesis runs derandomized (the same examples on every machine, so CI
cannot fail by chance) and without an example database in the work tree.  Session fixtures share
the costly computations that more than one test file asserts on."""

import pytest
from hypothesis import settings

settings.register_profile("ipmc", derandomize=True, database=None, deadline=None)
settings.load_profile("ipmc")


@pytest.fixture(scope="session")
def seed000_chain_quick(tmp_path_factory):
    """The bundled ``seed000_chain`` scenario run once in quick mode for the whole session, as
    ``ipmc run seed000_chain --quick`` runs it: ``(RunResult, output folder)``.  Its run is the
    slowest computation of the suite (about a minute of CPU); tests/scenarios/test_scenarios.py
    (every bundled scenario passes its checks and writes complete outputs) and
    tests/scenarios/test_seed000_chain.py (the chain's oracles) each ran it before, identically."""
    from scenarios.runner import run_scenario
    from scenarios.spec import bundled_scenarios, load_scenario

    path = next(p for p in bundled_scenarios() if p.stem == "seed000_chain")
    out = tmp_path_factory.mktemp("seed000_chain_quick")
    return run_scenario(load_scenario(path, quick=True), out, quiet=True), out
