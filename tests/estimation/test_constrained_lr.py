"""The constrained likelihood ratio of the linearised null (nullstats.constrained_lr and its
batched Gram form), against an oracle that does not enumerate active sets: for signature columns
S and a draw e, max over δ (one-sided components ≥ 0) of 2δᵀSᵀe − δᵀSᵀSδ equals
|e|² − min |Sδ − e|², the bounded linear least-squares problem solved by
``scipy.optimize.lsq_linear``.  Covered: one, two and three parameters, every one-sided pattern,
a zero column (a parameter left out), a batch over leading axes; and the one-parameter branch
(closed form, issue 27 item 6) gives the same numbers bit for bit as the pseudo-inverse it replaces."""

from __future__ import annotations

from itertools import product

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from physmodel.estimation.nullstats import _constrained_lr_gram, constrained_lr


def _oracle(S, E, one_sided):
    lo = np.array([0.0 if o else -np.inf for o in one_sided])
    out = []
    for e in E.T:
        keep = np.linalg.norm(S, axis=0) > 0                     # a zero column cannot move the fit
        if not keep.any():
            out.append(0.0)
            continue
        sol = lsq_linear(S[:, keep], e, bounds=(lo[keep], np.inf), tol=1e-13, lsmr_tol="auto", max_iter=500)
        out.append(float(e @ e - np.sum((S[:, keep] @ sol.x - e) ** 2)))
    return np.array(out)


@pytest.mark.parametrize("k", [1, 2, 3])
def test_constrained_lr_is_the_bounded_least_squares_gain(k):
    rng = np.random.default_rng(10 + k)
    S = rng.normal(size=(30, k))
    if k == 3:
        S[:, 1] += 0.8 * S[:, 0]                                  # correlated columns: active sets matter
    E = rng.normal(size=(30, 25)) * 2.0
    for one in product([False, True], repeat=k):
        got = constrained_lr(S, list(one), E)
        np.testing.assert_allclose(got, _oracle(S, E, one), rtol=1e-7, atol=1e-9)
        assert np.all(got >= 0)


def test_a_zero_column_is_a_parameter_left_out():
    rng = np.random.default_rng(4)
    S = rng.normal(size=(20, 2))
    S[:, 1] = 0.0
    E = rng.normal(size=(20, 15))
    for one in ([True, True], [False, True], [True, False]):
        np.testing.assert_allclose(constrained_lr(S, one, E), _oracle(S, E, one), rtol=1e-7, atol=1e-9)
    S1 = np.zeros((20, 1))
    assert np.array_equal(constrained_lr(S1, [True], E), np.zeros(15))


def test_batched_gram_equals_each_batch_member_and_the_one_parameter_branch_is_the_pseudo_inverse():
    rng = np.random.default_rng(5)
    S = rng.normal(size=(6, 40, 2))
    S[2, :, 0] = 0.0
    E = rng.normal(size=(40, 300))
    G = S.transpose(0, 2, 1) @ S
    B = S.transpose(0, 2, 1) @ E
    for one in ([True, True], [False, True]):
        got = _constrained_lr_gram(G, B, one)
        for i in range(6):
            np.testing.assert_allclose(got[i], _oracle(S[i], E, one), rtol=1e-7, atol=1e-9)
        # the one-parameter subsets alone, as the pseudo-inverse computes them (bit for bit)
        for j in range(2):
            g, b = G[:, j:j + 1, j:j + 1], B[:, j:j + 1, :]
            d = np.linalg.pinv(g) @ b
            want = np.where((not one[j]) | (d[:, 0] >= 0), np.sum(b * d, axis=-2), 0.0)
            want = np.where(want > 0, want, 0.0)
            assert np.array_equal(_constrained_lr_gram(g, b, [one[j]]), want)
