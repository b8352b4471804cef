"""The LM's per-start step control on Python floats gives exactly what the array expressions
it replaced give (written out here), including NaN/inf trial costs, pred <= 0, a gain ratio
whose cube overflows, stationary starts and zero steps."""

from __future__ import annotations

import numpy as np

from surrogate._lm_control import step_control


def _array_form(rr, rrt, pred, stationary, mu, nu, dx):
    with np.errstate(all="ignore"):
        actual = rr - rrt
        rho = actual / np.where(pred > 0, pred, np.nan)
        acc = (rho > 1e-4) & ~stationary
        mu = np.where(acc, mu * np.maximum(1 / 3, 1 - (2 * rho - 1) ** 3), mu * nu)
        nu = np.where(acc, 2.0, nu * 2.0)
        end = stationary | (~acc & ((mu > 1e30) | ~dx.any(axis=1)))
    return acc, mu, nu, end, actual


def test_step_control_equals_the_array_form_bit_for_bit():
    rng = np.random.default_rng(8)
    for _ in range(300):
        s = int(rng.integers(1, 6))
        rr = rng.uniform(0.5, 2.0, s) * 10.0 ** rng.uniform(-3, 3, s)
        rrt = rr * rng.uniform(0.0, 1.5, s)
        pred = (rr - rrt) * rng.uniform(0.5, 1.5, s) * rng.choice([1.0, -1.0, 0.0], s, p=[0.8, 0.1, 0.1])
        rrt[rng.random(s) < 0.1] = np.inf
        rrt[rng.random(s) < 0.1] = np.nan
        pred[rng.random(s) < 0.1] = 1e-300          # ρ huge: the cube overflows
        stationary = rng.random(s) < 0.15
        mu = 10.0 ** rng.uniform(-8, 31, s)
        nu = 2.0 ** rng.integers(1, 8, s).astype(float)
        dx = rng.normal(size=(s, 4)) * (rng.random((s, 1)) < 0.9)
        with np.errstate(all="ignore"):               # as inside LevenbergMarquardt.run
            got = step_control(rr, rrt, pred, stationary, mu.copy(), nu.copy(), dx)
        ref = _array_form(rr, rrt, pred, stationary, mu, nu, dx)
        assert list(got[0]) == ref[0].tolist() and list(got[3]) == ref[3].tolist()
        np.testing.assert_array_equal(got[1], ref[1])
        np.testing.assert_array_equal(got[2], ref[2])
        np.testing.assert_array_equal(np.array(got[4]), ref[4])
