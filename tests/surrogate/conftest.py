"""Fixtures for the surrogate tests (helpers live in surrogate_fixtures.py)."""

import numpy as np
import pytest
from surrogate_fixtures import FIT_TEMPS, TRUE_SCALING, TRUE_THETA, noisy_sweep

from surrogate import RationalModel, Structure


@pytest.fixture(scope="session")
def true_model():
    return RationalModel(Structure("zpk", 2, 3, 2), TRUE_THETA, TRUE_SCALING, (19.0, 55.0))


@pytest.fixture(scope="session")
def synthetic_sweep(true_model):
    return noisy_sweep(true_model, FIT_TEMPS, np.geomspace(0.1, 30, 40))
