"""Split of 1/G into polynomial + feedthrough + stable + anti-stable parts.

Oracle: direct evaluation of den(jw)/num(jw) with numpy.polyval, and numpy.roots for the
zeros; tolerances are a few hundred ulps times the conditioning of the evaluation.
"""

import control
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from inversion import (
    ImproperInverseError,
    InversionError,
    NonHyperbolicModelError,
    model_coefficients,
    split_inverse,
)
from inversion.examples import SEED000_DEN_35C, SEED000_NUM_35C, seed000_sensor_35c

W = np.logspace(-2, 4, 61)


def _direct(num, den, w):
    s = 1j * np.asarray(w)
    return np.polyval(den, s) / np.polyval(num, s)


def test_seed000_split_reproduces_inverse_and_partitions_zeros():
    sp = split_inverse(seed000_sensor_35c())
    H = _direct(SEED000_NUM_35C, SEED000_DEN_35C, W)
    assert np.max(np.abs(sp.frequency_response(W) / H - 1)) < 1e-10
    z = np.roots(SEED000_NUM_35C)
    assert sp.n_stable == 1 and sp.n_unstable == 3
    np.testing.assert_allclose(np.sort_complex(sp.stable_poles), np.sort_complex(z[z.real < 0]), rtol=1e-9)
    np.testing.assert_allclose(np.sort_complex(sp.unstable_poles), np.sort_complex(z[z.real > 0]), rtol=1e-9)
    # biproper: feedthrough is 1/b4
    assert sp.feedthrough == pytest.approx(1 / SEED000_NUM_35C[0], rel=1e-12)
    assert sp.derivative_coefficients.size == 0
    assert sp.r0 == pytest.approx(min(z[z.real > 0].real), rel=1e-10)
    assert sp.auto_preview_s == pytest.approx(4 / sp.r0, rel=1e-14)
    # pieces agree with the parts evaluated separately
    parts = (sp.frequency_response(W, "polynomial") + sp.frequency_response(W, "stable")
             + sp.frequency_response(W, "unstable"))
    np.testing.assert_allclose(parts, sp.frequency_response(W), rtol=1e-13)
    # control objects for users
    hu = sp.unstable_tf()
    assert isinstance(hu, control.TransferFunction)
    np.testing.assert_allclose(hu(1j * W), sp.frequency_response(W, "unstable"), rtol=1e-8)


def test_statespace_and_pair_inputs_agree():
    G = seed000_sensor_35c()
    a = split_inverse(G).frequency_response(W)
    b = split_inverse(control.ss(G)).frequency_response(W)
    c = split_inverse((list(SEED000_NUM_35C), list(SEED000_DEN_35C))).frequency_response(W)
    np.testing.assert_allclose(a, b, rtol=1e-8)
    np.testing.assert_allclose(a, c, rtol=1e-13)


@settings(max_examples=40, deadline=None)
@given(
    stable=st.lists(st.floats(0.5, 2000.0), min_size=0, max_size=3),
    unstable=st.lists(st.floats(0.5, 2000.0), min_size=0, max_size=3),
    pair=st.one_of(st.none(), st.tuples(st.floats(-500, 500).filter(lambda x: abs(x) > 1.0),
                                        st.floats(1.0, 800.0))),
    gain=st.floats(0.01, 100.0),
)
def test_random_hyperbolic_models(stable, unstable, pair, gain):
    zeros = [-x for x in stable] + list(unstable)
    if pair is not None:
        zeros += [complex(pair[0], pair[1]), complex(pair[0], -pair[1])]
    # (near-)repeated zeros make repeated inverse poles: a modal split then loses accuracy like
    # eps^(1/m) for multiplicity m, which is the problem's conditioning, not a defect; keep them apart
    z = np.array(zeros, dtype=complex)
    for i in range(z.size):
        for j in range(i):
            assume(abs(z[i] - z[j]) > 0.05 * max(abs(z[i]), abs(z[j])))
    num = gain * np.real(np.poly(zeros)) if zeros else np.array([gain])
    den = np.atleast_1d(np.real(np.poly(-np.linspace(3.0, 900.0, len(zeros)))))
    sp = split_inverse((num, den))
    H = _direct(num, den, W)
    # conditioning of the direct evaluation itself ~ sum|terms|/|value|
    rel = np.abs(sp.frequency_response(W) / H - 1)
    assert np.max(rel) < 1e-7
    assert sp.n_unstable == sum(1 for z in zeros if np.real(z) > 0)
    if sp.n_unstable:
        # repeated zeros are computed to ~eps**(1/multiplicity) only: 1e-4 covers triple zeros
        assert sp.r0 == pytest.approx(min(np.real(z) for z in zeros if np.real(z) > 0), rel=1e-4)
    else:
        assert sp.r0 == np.inf and sp.auto_preview_s == 0.0


def test_clustered_zeros_high_order():
    # 8 zeros: two tight clusters on both sides of the axis
    zeros = [-10.0, -10.001, -10.002, -10.003, 10.0, 10.001, 10.002, 10.003]
    num = np.real(np.poly(zeros))
    den = np.real(np.poly(-np.geomspace(1.0, 1000.0, 8)))
    sp = split_inverse((num, den))
    assert (sp.n_stable, sp.n_unstable) == (4, 4)
    w = np.logspace(-1, 3, 41)
    H = _direct(num, den, w)
    # the clustered zeros make 1/G itself ill-conditioned near w ~ 10; compare in relative terms
    assert np.max(np.abs(sp.frequency_response(w) / H - 1)) < 1e-5


def test_zero_on_imaginary_axis_is_rejected_with_its_value():
    with pytest.raises(NonHyperbolicModelError, match=r"0\+31\.4\dj|31\.4"):
        split_inverse((np.real(np.poly([31.4j, -31.4j, -5.0])), [1, 3, 3, 1]))
    with pytest.raises(NonHyperbolicModelError, match="imaginary axis"):
        split_inverse(([1.0, 0.0], [1.0, 2.0]))        # zero at s = 0 (high-pass sensor)
    assert issubclass(NonHyperbolicModelError, ValueError)


def test_improper_inverse_default_error_and_options():
    num, den = [100.0], [1.0, 14.0, 100.0]       # relative degree 2
    with pytest.raises(ImproperInverseError, match="relative degree 2"):
        split_inverse((num, den))
    d = split_inverse((num, den), improper="differentiate")
    # H = s^2/100 + 0.14 s + 1
    np.testing.assert_allclose(d.derivative_coefficients, [0.14, 0.01], rtol=1e-13)
    assert d.feedthrough == pytest.approx(1.0, rel=1e-13)
    assert d.n_stable == d.n_unstable == 0
    wf = 2000.0
    f = split_inverse((num, den), improper="filter", filter_bandwidth=wf)
    w = np.logspace(-1, 4, 30)
    expect = _direct(num, den, w) * (wf / (1j * w + wf)) ** 2
    np.testing.assert_allclose(f.frequency_response(w), expect, rtol=1e-9)
    with pytest.raises(InversionError, match="filter_bandwidth"):
        split_inverse((num, den), improper="filter")
    with pytest.raises(InversionError, match="improper"):
        split_inverse((num, den), improper="ignore")
    with pytest.raises(InversionError, match="only used with improper='filter'"):
        split_inverse((num, den), filter_bandwidth=10.0)


@pytest.mark.parametrize(
    "model, match",
    [
        (([1.0, 2.0, 3.0], [1.0, 2.0]), "proper"),
        (([0.0, 0.0], [1.0, 2.0]), "identically zero"),
        (([1.0, np.nan], [1.0, 2.0]), "finite"),
        ((["a"], [1.0]), "real numbers"),
        (object(), "cannot read"),
    ],
)
def test_invalid_models(model, match):
    with pytest.raises(InversionError, match=match):
        split_inverse(model)


def test_discrete_mimo_and_surrogate_like_models_rejected():
    with pytest.raises(InversionError, match="continuous-time"):
        split_inverse(control.tf([1, 0.5], [1, 0.2], 0.01))
    with pytest.raises(InversionError, match="SISO"):
        split_inverse(control.ss(-np.eye(2), np.eye(2), np.eye(2), np.eye(2)))

    class Surrogate:
        def at(self, T):
            return None

    with pytest.raises(InversionError, match=r"\.at\("):
        split_inverse(Surrogate())


def test_model_coefficients_strips_leading_zeros():
    num, den = model_coefficients(([0.0, 0.0, 2.0, 1.0], [0.0, 1.0, 3.0]))
    np.testing.assert_array_equal(num, [2.0, 1.0])
    np.testing.assert_array_equal(den, [1.0, 3.0])


def test_l1_norm_of_first_order_parts_is_analytic():
    # H = (s + 2)/(s + 10)(s - 5) ... use G = (s+10)(s-5)/((s+1)(s+2)) so H has poles -10, +5
    sp = split_inverse((np.poly([-10.0, 5.0]), np.poly([-1.0, -2.0])))
    l1s, l1u = sp.l1_norms()
    # first-order parts: |residue| / |pole|
    rs = sp.C_s @ sp.B_s
    ru = sp.C_u @ sp.B_u
    assert l1s == pytest.approx(abs(rs) / 10.0, rel=1e-4)
    assert l1u == pytest.approx(abs(ru) / 5.0, rel=1e-4)
