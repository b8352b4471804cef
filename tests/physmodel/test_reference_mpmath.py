"""The fast numpy path against the 50-digit mpmath reference: ≤ 1e-12 relative, everywhere.

Grid: 1e-4 .. 1e5 Hz, 0 .. 90 °C, every named parameter set and the edge cases the physics
allows (ideal electrodes r1 = r2 = 0, no leakage Rp = inf, huge γ, tiny γ, tiny θL, huge θL).
Warnings are errors in this suite, so overflow or 0/0 anywhere fails the test.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from mpmath_reference import reference

from physmodel import ActuatorModel, SensorModel, available_parameter_sets, get_parameter_set, state_at
from physmodel.params import STATE_FIELDS

RTOL = 1e-12
FREQS = np.logspace(-4, 5, 19)
TEMPS = np.array([0.0, 45.0, 90.0])


def edge_cases():
    base = get_parameter_set("seed002_table3")
    return {
        "ideal_electrodes": base.replace(r1_sheet=0.0, r2_specific=0.0),
        "no_leakage": base.replace(Rp_specific=np.inf),
        "ideal_and_no_leakage": base.replace(r1_sheet=0.0, r2_specific=0.0, Rp_specific=np.inf),
        "huge_gamma": base.replace(kappa_e=1e-10, C_minus=5e4, h=1e-3),      # γ0 ~ 1e7
        "small_gamma": base.replace(C_minus=1e-9, h=1e-6),                    # γ0 ~ 1e-5: series for γ − tanh γ
        "tiny_line": base.replace(r1_sheet=1e-14),                            # θL ~ 1e-8: series for X, x coth x
        "huge_line": base.replace(r1_sheet=1e6, Rp_specific=1e-6),            # Re θL ≫ 40
    }


def all_sets():
    sets = {name: get_parameter_set(name) for name in available_parameter_sets()}
    sets.update(edge_cases())
    return sets


def _rows(params, temps):
    stt = state_at(params, temps)
    for i_T in range(len(temps)):
        yield i_T, {k: float(getattr(stt, k)[0, i_T, 0]) for k in STATE_FIELDS}


def _rel(a, b):
    return np.abs(a - b) / np.abs(b)


@pytest.mark.parametrize("name", sorted(all_sets()))
def test_fast_path_matches_mpmath(name):
    p = all_sets()[name]
    act = ActuatorModel(p).frequency_response(FREQS, TEMPS)
    sens = {k: SensorModel(p, kernel=k).frequency_response(FREQS, TEMPS)["S"] for k in ("boundary_charge", "reciprocal")}
    worst = 0.0
    for i_T, row in _rows(p, TEMPS):
        for i_f, f in enumerate(FREQS):
            s = 2j * np.pi * f
            for kernel in ("boundary_charge", "reciprocal"):
                ref = reference(row, s, kernel)
                got = sens[kernel][0, i_T, i_f]
                err = _rel(got, ref["S"])
                assert err <= RTOL, f"{name} S[{kernel}] at {f:g} Hz, {TEMPS[i_T]} °C: rel err {err:.2e}"
            for q in ("Z", "H", "G", "M"):
                err = _rel(act[q][0, i_T, i_f], ref[q])
                worst = max(worst, err)
                assert err <= RTOL, f"{name} {q} at {f:g} Hz, {TEMPS[i_T]} °C: got {act[q][0, i_T, i_f]!r}, mpmath {ref[q]!r}, rel err {err:.2e}"
    assert np.isfinite(worst)


def test_batch_and_grid_layouts_agree_with_single_evaluation():
    """A batch of sets, short rows (row blocks) and long rows (chunks) give identical numbers."""
    sets = [get_parameter_set("seed002_table3"), get_parameter_set("dev"), get_parameter_set("seed002_table2")]
    T = [5.0, 40.0]
    f_short = np.logspace(-1, 3, 7)
    batch = ActuatorModel(sets, chunk_size=16).frequency_response(f_short, T)
    for i, p in enumerate(sets):
        single = ActuatorModel(p, chunk_size=3).frequency_response(f_short, T)
        for q in ("Z", "M"):
            np.testing.assert_allclose(batch[q][i], single[q][0], rtol=1e-14, atol=0)


def test_general_complex_s_matches_mpmath():
    """Off the imaginary axis (what a Laplace inversion needs): still the principal, even branch."""
    p = get_parameter_set("seed002_table3")
    s_pts = np.array([-5.0 + 30j, -50.0 - 10j, 3.0 + 0.5j, -1e3 + 1e4j, 1e-3 - 2e-3j])
    got = ActuatorModel(p).evaluate(s_pts, [25.0])
    (_, row), = list(_rows(p, [25.0]))
    for i, s in enumerate(s_pts):
        ref = reference(row, complex(s))
        for q in ("Z", "H", "M"):
            assert _rel(got[q][0, 0, i], ref[q]) <= RTOL, (q, s)


positive = lambda lo, hi: st.floats(np.log10(lo), np.log10(hi)).map(lambda e: 10.0**e)


@settings(max_examples=40, deadline=None)
@given(
    L=positive(5e-3, 60e-3), W=positive(0.3e-3, 15e-3), h=positive(50e-6, 300e-6),
    d=positive(1e-12, 1e-9), C=positive(100, 3000), kappa=positive(1e-8, 1e-5),
    r1=st.one_of(st.just(0.0), positive(1e-3, 1e3)), r2=st.one_of(st.just(0.0), positive(1e-8, 1e-3)),
    Rp=st.one_of(st.just(np.inf), positive(1e-3, 1e2)), E=positive(2e7, 2e9), xi=positive(0.01, 0.9),
    f=positive(1e-4, 1e5), T=st.floats(0, 90),
)
def test_property_matches_mpmath_over_parameter_box(L, W, h, d, C, kappa, r1, r2, Rp, E, xi, f, T):
    p = get_parameter_set("dev").replace(L=L, W=W, h=h, d=d, C_minus=C, kappa_e=kappa, r1_sheet=r1,
                                         r2_specific=r2, Rp_specific=Rp, E=E, xi=xi)
    got = ActuatorModel(p).frequency_response([f], [T])
    S = SensorModel(p).frequency_response([f], [T])["S"][0, 0, 0]
    (_, row), = list(_rows(p, [T]))
    ref = reference(row, 2j * np.pi * f)
    for q in ("Z", "H", "M"):
        v = got[q][0, 0, 0]
        assert np.isfinite(v)
        assert _rel(v, ref[q]) <= RTOL, (q, v, ref[q])
    assert _rel(S, ref["S"]) <= RTOL


def test_kernels_on_both_sides_of_every_series_switch():
    """line_kernels and tanh_and_gmt against mpmath for |arg| from 1e-9 to 1e3 across the branch."""
    import mpmath as mp

    from physmodel import numerics

    mags = np.logspace(-9, 3, 241)
    # dense around the switches
    mags = np.concatenate([mags, numerics.X_SERIES_BELOW * np.array([0.5, 0.9, 0.999, 1.001, 1.1, 2]),
                           numerics.GMT_SERIES_BELOW * np.array([0.5, 0.9, 0.999, 1.001, 1.1, 2]),
                           numerics.EXP_FAST_ABOVE * np.array([0.9, 0.999, 1.001, 1.1])])
    for phase in (0.0, np.pi / 8, np.pi / 4):     # principal sqrt of a passive admittance: 0..45°
        z = mags * np.exp(1j * phase)
        X, xcoth = numerics.line_kernels(z)
        t, gmt = numerics.tanh_and_gmt(z)
        t = np.broadcast_to(t, z.shape)
        with mp.workdps(60):
            for i, zi in enumerate(z):
                m = mp.mpc(zi.real, zi.imag)
                refX = (m * mp.tanh(m) + mp.sech(m) - 1) / m**2
                refC = m / mp.tanh(m)
                refT = mp.tanh(m)
                refG = m - mp.tanh(m)
                for got, ref, what in ((X[i], refX, "X"), (xcoth[i], refC, "xcoth"), (t[i], refT, "tanh"), (gmt[i], refG, "gmt")):
                    err = abs(mp.mpc(got.real, got.imag) - ref) / abs(ref)
                    assert err <= RTOL, f"{what}({zi!r}): rel err {float(err):.2e}"
