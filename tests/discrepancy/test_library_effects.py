"""The library's new effects (issue 11) against direct solutions they did not produce:

* ``second_mode`` (the Euler–Bernoulli modal expansion of physmodel.beam, driven by the moment
  profile of the electrode line) against a finite-element cantilever with Rayleigh damping solved
  directly in the frequency domain under the same distributed moment (tests/discrepancy/oracles.py);
* the modal participations against the printed values for a uniform moment and Σπ_n = 1;
* ``series_cpe`` against nodal analysis of the two-rail electrode ladder driven through the CPE;
* the same effects against the independent generator (its own implementation of each effect).
"""

from __future__ import annotations

import beam_circuit_oracles as oracles
import independent_generator as gen
import independent_physics as ip
import numpy as np
import pytest

from physmodel import ActuatorModel, IPMCParameters, beam, electrode, get_parameter_set
from physmodel.effects import EffectModel
from physmodel.params import STATE_FIELDS

P = get_parameter_set("seed002_table3").replace(r1_sheet=500.0)      # a clearly decaying moment


def _line_x(params, f_hz, T_c):
    st = ActuatorModel(params).state([T_c])
    p = {k: getattr(st, k) for k in STATE_FIELDS}
    s = 2j * np.pi * np.asarray(f_hz)[None, None, :]
    A = electrode.strip_terms(p, s, want_xcoth=False).A
    return electrode.line_argument(A, p["r1"], p["L"])[0, 0], st


def test_uniform_moment_participations():
    pi = beam.moment_participation(0.0, 40).real
    np.testing.assert_allclose(pi[:4], [0.890772, 0.078774, 0.016495, 0.006018], atol=1e-6)
    # Σ π_n = 1: the modes above 40 carry the asymptotic tail π_n → 8/λ_n³, λ_n → (n − ½)π
    tail = np.sum(8.0 / ((np.arange(41, 200000) - 0.5) * np.pi) ** 3)
    assert 1 - pi.sum() == pytest.approx(tail, rel=0.02)
    lam = beam.cantilever_roots(6)
    assert np.all(np.abs(np.cos(lam) * np.cosh(lam) + 1) < 1e-9 * np.cosh(lam))


@pytest.mark.parametrize("nu", [1.0, 0.6])
def test_second_mode_against_finite_element_cantilever(nu):
    """M_effect/H (weight 1) equals the FE tip deflection over its static value under the moment
    cosh(x(1 − ξ))/cosh x of the library's own electrode line at each frequency."""
    T_c = 26.85
    f = np.array([0.3, 3.0, 11.0, 25.0, 60.0, 90.0])
    x, st = _line_x(P, f, T_c)
    assert np.max(np.abs(x)) > 1.0                     # the moment really decays along the strip
    m = EffectModel(P, "actuator", {"second_mode": {"weight": 1.0, "viscous_share": nu}}).frequency_response(
        f, [T_c], quantities=("M", "H"))
    lib = m["M"][0, 0] / m["H"][0, 0]
    w1, xi = float(st.omega_n.ravel()[0]), float(st.xi.ravel()[0])
    lam1 = beam.cantilever_roots(1)[0]
    scale = lam1**2 / w1                               # FE beam with EI = ρA = L = 1: ω1 = λ1²
    a, b = 2 * xi * nu * lam1**2, 2 * xi * (1 - nu) / lam1**2
    fe = []
    for fk, xk in zip(f, x):
        tip, tip0 = oracles.fe_cantilever_tip([2j * np.pi * fk * scale],
                                              lambda z, xk=xk: np.cosh(xk * (1 - z)) / np.cosh(xk),
                                              n_el=80, rayleigh=(a, b))
        fe.append(tip[0] / tip0)
    np.testing.assert_allclose(lib, np.array(fe), rtol=2e-4)


def test_second_mode_matches_the_independent_generator():
    """The generator's own modal sum (quadrature participations) and the library's closed form."""
    x = np.array([0.0, 0.8 + 0.6j, 2.5 + 2.0j, 1.8751040687119611])
    np.testing.assert_allclose(beam.moment_participation(x, 6), ip.modal_participation(x, 6), rtol=1e-7, atol=1e-12)
    s = 2j * np.pi * np.logspace(-1, 2, 25)
    for nu in (1.0, 0.5):
        np.testing.assert_allclose(beam.modal_tip_response(s, 70.0, 0.18, 1.2 + 0.8j, 6, nu),
                                   ip.modal_mechanics(1.2 + 0.8j, s, 70.0, 0.18, 6, nu), rtol=1e-12)


@pytest.mark.parametrize("cpe", [dict(S_area=0.05, n=0.8), dict(S_area=0.5, n=0.95)])
def test_series_cpe_against_ladder(cpe):
    """Nodal analysis of the ladder driven through Z_cpe = S'/(W L)(jω)^−n: input impedance and the
    actuation ∫(L − z) v dz relative to direct drive, Richardson-extrapolated (n = 100, 200)."""
    T_c = 25.0
    f = np.array([0.05, 0.5, 3.0, 20.0, 50.0])
    st = ActuatorModel(P).state([T_c])
    p = {k: getattr(st, k) for k in STATE_FIELDS}
    s = 2j * np.pi * f
    y = electrode.strip_terms(p, s[None, None, :], want_xcoth=False).A[0, 0] / 2       # per length, both rails
    r1, L, W = float(p["r1"].ravel()[0]), P.L, P.W
    zc = cpe["S_area"] / (W * L) / (2 * np.pi * f) ** cpe["n"] * np.exp(-0.5j * np.pi * cpe["n"])
    lib = EffectModel(P, "actuator", {"series_cpe": cpe}).frequency_response(f, [T_c], quantities=("M", "Z"))
    base = ActuatorModel(P).frequency_response(f, [T_c], quantities=("M", "Z"))
    est = {}
    for n in (100, 200):
        Zs, ratio = [], []
        for k in range(f.size):
            Zin, z, v = oracles.ladder_with_series(y[k], r1, L, n, zc[k])
            _, _, v0 = oracles.ladder_with_series(y[k], r1, L, n, None)
            wts = np.full(n + 1, L / n)
            wts[[0, -1]] /= 2
            ratio.append(np.sum(wts * (L - z) * v) / np.sum(wts * (L - z) * v0))
            Zs.append(Zin)
        est[n] = (np.array(Zs), np.array(ratio))
    Z_ex = (4 * est[200][0] - est[100][0]) / 3
    R_ex = (4 * est[200][1] - est[100][1]) / 3
    np.testing.assert_allclose(lib["Z"][0, 0], Z_ex, rtol=1e-5)
    np.testing.assert_allclose(lib["M"][0, 0] / base["M"][0, 0], R_ex, rtol=1e-5)


def test_series_cpe_matches_the_independent_generator():
    b = gen._at_reference(gen.START_SEED002, 25.0, False)
    lib = IPMCParameters.from_dict(gen.library_fields(b))
    f, T = gen.FREQUENCIES_HZ, [25.0, 40.0]
    q_area, n = 20.0, 0.8
    mine = ip.actuator_response(b, f, T, {"series_cpe": {"q_area": q_area, "n": n}})
    got = EffectModel(lib, "actuator", {"series_cpe": {"S_area": 1.0 / q_area, "n": n}}).frequency_response(
        f, T, quantities=("M", "Z"))
    np.testing.assert_allclose(got["M"][0], mine["M"], rtol=1e-9)
    np.testing.assert_allclose(got["Z"][0], mine["Z"], rtol=1e-9)
