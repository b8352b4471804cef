"""The one-polynomial form of the fused pass's all-pole cascade (inversion._sections): the search
for the best-rounded coefficients, the conditions under which its running-error probe is run, and
the cache that keeps the decision per cascade.

Oracles: mpmath at 60 digits for the candidates' errors, the closed-form impulse response and gain
of a pole pair, and the seed 000 sensor's known outcomes (polynomial at 20 kHz)."""

import itertools
import math

import mpmath as mp
import numpy as np
import pytest

from inversion import _sections as sec
from inversion import split_inverse
from inversion._discrete import Plan
from inversion.examples import seed000_sensor_35c

LONGDOUBLE_WIDER = bool(np.finfo(np.longdouble).eps < 1e-18)
G35 = seed000_sensor_35c("coefficients")
#: right-half-plane zeros 600 and 15±150j rad/s: a resonant third-order anticausal part
RESONANT = (np.real(np.poly([600.0, 15.0 + 150.0j, 15.0 - 150.0j])), np.poly([-1000.0] * 3))


def _anticausal_sections(G, fs):
    plan = Plan(split_inverse(G), 1.0 / fs, None)
    poles = np.linalg.eigvals(plan.anti_phi)
    return sec.all_pole_sections(np.where(np.abs(poles.imag) <= 1e-12, poles.real, poles))


def _mp_errors(sos, candidates):
    """Max over the unit-circle test points of |cand(1/z) / exact(1/z) - 1| for each candidate,
    the exact polynomial the product of the rows (doubles, exact) formed in mpmath."""
    mp.mp.dps = 60
    exact = [mp.mpf(1)]
    for row in sos:
        q = [mp.mpf(float(v)) for v in row[3:]]
        exact = [sum(exact[j] * q[i - j] for j in range(len(exact)) if 0 <= i - j < len(q))
                 for i in range(len(exact) + len(q) - 1)]
    while exact[-1] == 0:
        exact.pop()
    zinv = [mp.mpc(complex(z)) for z in 1.0 / np.exp(1j * np.pi * np.concatenate((np.logspace(-7, 0, 36), [0.0])))]
    ref = [_mp_horner(exact, z) for z in zinv]
    out = []
    for cand in candidates:
        c = [mp.mpf(float(v)) for v in cand]
        out.append(max(abs(_mp_horner(c, z) / r - 1) for z, r in zip(zinv, ref)))
    return exact, out


def _mp_horner(coeffs, x):
    """``sum_i coeffs[i] x**i`` in mpmath."""
    out = mp.mpf(0)
    for c in reversed(coeffs):
        out = out * x + c
    return out


@pytest.mark.skipif(not LONGDOUBLE_WIDER, reason="np.longdouble is not wider than double here")
@pytest.mark.parametrize("G, fs", [(G35, 20e3), (RESONANT, 20e3)])
def test_the_chosen_coefficients_are_the_best_candidate_by_an_mpmath_evaluation(G, fs):
    # every double within 2 ulp of each exact coefficient (order 3: 5**3 candidates), their errors
    # at the test points evaluated in mpmath; the search (in double, on the residuals from the
    # exact coefficients) must choose one of the best: its error within 1e-9 of theirs (exact ties
    # are common, e.g. +k ulp on one coefficient and -k on the next leave a(1) as it is; the
    # double evaluation tells errors apart to ~1e-15).  Seed 000 at 20 kHz: 1.56e-11.  RESONANT:
    # the former search, which evaluated the candidates in np.clongdouble (a difference of values
    # of the size of a(1), 3e-6 of the coefficients: ~2 digits of the errors left), chose one
    # 2.9e-4 above the best (1.20261e-10 vs 1.20226e-10).
    sos = _anticausal_sections(G, fs)
    chosen = sec.best_rounded_polynomial(sos)
    exact, _ = _mp_errors(sos, [])
    m = len(exact) - 1
    assert m == 3 and chosen is not None and chosen.size == m + 1
    opts = []
    for c in exact[1:]:
        near = float(c)
        up, down = [near], [near]
        for _ in range(2):
            up.append(float(np.nextafter(up[-1], np.inf)))
            down.append(float(np.nextafter(down[-1], -np.inf)))
        opts.append(down[:0:-1] + up)
    cands = [np.array([1.0, *t]) for t in itertools.product(*opts)]
    _, errs = _mp_errors(sos, [chosen, *cands])
    assert errs[0] <= min(errs[1:]) * (1 + 1e-9)
    if G is G35:
        assert float(errs[0]) == pytest.approx(1.56e-11, rel=0.01)


@pytest.mark.skipif(not LONGDOUBLE_WIDER, reason="np.longdouble is not wider than double here")
def test_poles_too_clustered_for_the_exact_product_give_no_polynomial_and_no_warning():
    # 8 real poles within 5e-3 of z = 1: their product at z = 1 (2.5e-21 of coefficients up to 69)
    # is below what np.longdouble resolves (it comes out as 0 with numpy 2.4, as 3e-18 of rounding
    # with numpy 1.24); the search must say None, not divide by it (warnings are errors in this
    # suite), pick a NaN candidate or fit the rounding
    poles = np.exp(-np.linspace(1e-3, 5e-3, 8))
    sos = sec.all_pole_sections(poles.astype(complex))
    assert sec.best_rounded_polynomial(sos) is None


def _pair_sections(r, theta):
    return sec.all_pole_sections(np.array([r * np.exp(1j * theta), r * np.exp(-1j * theta)]))


def test_probe_length_is_twenty_slowest_time_constants_for_real_poles():
    for poles, length in [([0.9, 0.95], 2000), ([0.999, 0.99, 0.5], 20_000), ([0.9999], None)]:
        sos = sec.all_pole_sections(np.array(poles, dtype=complex))
        expected = length if length is None else max(2000, math.ceil(20.0 / (1.0 - max(poles))))
        assert sec.probe_length(sos) == expected


def test_probe_length_refuses_a_pair_whose_gain_peaks_away_from_dc_or_whose_impulse_response_changes_sign():
    # a pole pair r e^(±j theta): |a(e^jw)|**2 is a quadratic in cos w with its vertex at
    # cos w = cos(theta) (1 + r**2) / (2 r), so the gain peaks at DC iff cos(theta) >= 2 r / (1 + r**2);
    # its impulse response is r**k sin((k + 1) theta) / sin(theta)
    r = 0.999
    critical = math.acos(2.0 * r / (1.0 + r * r))
    k = np.arange(200_000)
    for factor, peak_at_dc in [(2.0, False), (0.9, True), (0.1, True)]:
        theta = factor * critical
        assert (math.cos(theta) * (1.0 + r * r) / (2.0 * r) >= 1.0) == peak_at_dc
        h = r**k * np.sin((k + 1) * theta) / math.sin(theta)
        l1_excess = np.sum(np.abs(h)) / np.sum(h) - 1.0
        # 0.9: h goes negative after pi / theta samples while the gain still peaks at DC (l1 norm
        # 6% above the DC gain); 0.1: that lobe is e**-31 of the peak, below any rounding
        assert (l1_excess > 1e-3) == (factor != 0.1) and (l1_excess < 1e-12) == (factor == 0.1)
        assert (sec.probe_length(_pair_sections(r, theta)) is not None) == (factor == 0.1)


@pytest.mark.skipif(not LONGDOUBLE_WIDER, reason="np.longdouble is not wider than double here")
def test_the_kept_decision_follows_the_probe_limit(monkeypatch):
    # the decision is kept per cascade (lru_cache), under the limits it was made with: the seed 000
    # probe at 20 kHz needs 11,281 samples, so with PROBE_MAX below that the sections are kept even
    # though the same cascade was decided (polynomial) before
    split = split_inverse(G35)
    assert Plan(split, 1.0 / 20e3, 4919).fused.sos is None
    monkeypatch.setattr(sec, "PROBE_MAX", 10_000)
    assert Plan(split, 1.0 / 20e3, 4919).fused.sos is not None
    monkeypatch.setattr(sec, "PROBE_MAX", 1 << 15)
    assert Plan(split, 1.0 / 20e3, 4919).fused.sos is None
