"""The look-elsewhere scan of the linearised null (physmodel.estimation.nullstats.scan_lr).

Oracle: a bump in log-magnitude, ln|G| = a·exp(−(log10 f − c)²/(2w²)), whose centre c is not
identified under the null (a = 0).  With a baseline gain column projected out, the likelihood ratio
of "a ≥ 0 and c free" is, per noise draw e, sup_c max(0, φ_c·e)²/|φ_c|² (φ_c the projected bump):
with e the draw of −residual and φ_c entering with a minus sign (the residual is ln(data/model)),
evaluated here on a grid 12× finer than the scan's, directly from that formula (Davies 1987), not
through the library.  A scan on a subset of that supremum's points can never exceed it; with the bump
much wider than the scan's grid it must reach it to well under 1 %, and the 95 % quantile must sit far
above the fixed-centre one-sided value χ̄² = 2.71 (the look-elsewhere effect the old threshold missed).
"""

from __future__ import annotations

import math

import numpy as np

from physmodel.data.sweep import FrequencySweep
from physmodel.effects.base import EffectParameter
from physmodel.estimation.nullstats import _needs_others, scan_lr
from physmodel.estimation.signatures import effect_signature

N = 40
F = np.logspace(-1, 2, N)
W = 0.3                      # bump width [decades], ≫ the scan's grid step 3/255
AMP = EffectParameter("amp", "1", 0.0, 0.0, 5.0, 1.0)
CENTRE = EffectParameter("centre", "1", 0.5, -1.0, 2.0, 1.0)
PARAMS = (AMP, CENTRE)
DATA = FrequencySweep(np.full(N, 25.0), F, np.ones(N, complex), np.full(N, 20 / math.log(10)),
                      np.full(N, math.degrees(1.0)), "voltage", "V", "tip_displacement", "mm")
ONES = np.ones(N)


def bump(c):
    return np.exp(-((np.log10(F) - c) ** 2) / (2 * W * W))


def predict_many(points):
    return np.array([np.exp(p.get("bump.amp", 0.0) * bump(p.get("bump.centre", 0.5))) for p in points], dtype=complex)


def _setup(draws=3000, seed=5):
    r0 = np.zeros(2 * N)                                 # data = baseline exactly (residuals of the null)
    J0 = np.zeros((2 * N, 1))
    J0[:N, 0] = 1.0                                      # a free gain: constant in log-magnitude
    Q0 = J0 / np.linalg.norm(J0)
    E = np.random.default_rng(seed).standard_normal((2 * N, draws))
    Ep = E - Q0 @ (Q0.T @ E)
    return r0, Q0, Ep


def _oracle(Ep, Q0, n=255 * 12 + 1):          # contains the scan's 256 grid points
    best = np.zeros(Ep.shape[1])
    for c in np.linspace(-1.0, 2.0, n):
        phi = np.concatenate([bump(c), np.zeros(N)])
        phi = phi - Q0[:, 0] * (Q0[:, 0] @ phi)
        u = -phi / np.linalg.norm(phi)            # residuals are ln(data/model): a ≥ 0 lowers them
        best = np.maximum(best, np.maximum(u @ Ep, 0.0) ** 2)
    return best


def test_scan_reaches_the_davies_supremum_and_never_exceeds_it():
    r0, Q0, Ep = _setup()
    scan = scan_lr(predict_many, {}, "bump", PARAMS, np.array([False, True]), r0, DATA, ONES, ONES, Q0, Ep)
    sup = _oracle(Ep, Q0)
    assert np.all(scan <= sup * (1 + 1e-6) + 1e-9)
    assert abs(np.quantile(scan, 0.95) / np.quantile(sup, 0.95) - 1) < 0.005
    # the look-elsewhere effect is real here: far above the fixed-centre one-sided quantile
    assert np.quantile(scan, 0.95) > 2.71 + 2.0


def test_centre_is_flagged_as_acting_only_with_the_amplitude_on():
    r0, Q0, _ = _setup(draws=10)
    S, _ = effect_signature(predict_many, {}, "bump", r0, DATA, ONES, ONES, PARAMS)
    flags = _needs_others(predict_many, {}, "bump", PARAMS, S, r0, DATA, ONES, ONES, 0.1)
    assert flags.tolist() == [False, True]
