"""Sanathanan–Koerner stops once its weights have converged (issue 17), and what it returns
is still the fixed point: checked against a known rational response and against the
iterations run to the end."""

import numpy as np

from surrogate._init import SK_WEIGHT_CHANGE, sanathanan_koerner


def _response(w):
    """H = (0.5 + 2s + s²)/(s³ + 1.4s² + 2.1s + 0.8), exact (the oracle's coefficients)."""
    s = 1j * w
    return (0.5 + 2 * s + s ** 2) / (s ** 3 + 1.4 * s ** 2 + 2.1 * s + 0.8)


def test_exact_data_stops_early_at_the_true_denominator():
    w = np.geomspace(0.05, 20, 60)
    its = sanathanan_koerner(w, _response(w), 2, 3)
    assert len(its) < 9                       # stopped before the 8 reweightings
    num, den = its[-1]
    np.testing.assert_allclose(den, [0.8, 2.1, 1.4, 1.0], rtol=1e-8)
    np.testing.assert_allclose(num, [0.5, 2.0, 1.0], rtol=1e-8)


def test_noisy_data_last_iterate_close_to_the_full_run():
    rng = np.random.default_rng(3)
    w = np.geomspace(0.05, 20, 60)
    h = _response(w) * np.exp(0.02 * rng.standard_normal(60) + 0.02j * rng.standard_normal(60))
    early = sanathanan_koerner(w, h, 2, 3)
    full = sanathanan_koerner(w, h, 2, 3, weight_change=0.0)
    assert len(full) == 9 and len(early) < len(full)
    # the iterates agree up to where the early run stopped (same arithmetic)
    for (ne, de), (nf, df) in zip(early, full, strict=False):
        np.testing.assert_array_equal(de, df)
    # the weights 1/|D| of the early answer are within the stopping threshold (a few times,
    # for the geometric tail of a linearly converging iteration) of the converged ones
    d_early = np.abs(np.polyval(early[-1][1][::-1], 1j * w))
    d_full = np.abs(np.polyval(full[-1][1][::-1], 1j * w))
    assert np.max(np.abs(d_early / d_full - 1)) <= 5 * SK_WEIGHT_CHANGE
