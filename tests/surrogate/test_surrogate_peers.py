"""Per-temperature fit against the classic fitters at equal order (4/4) on a stand-in sweep."""

import warnings

import numpy as np
import pytest
from surrogate_standin import physics_sweep

from surrogate import RationalFit, levy, relative_rms_error


@pytest.fixture(scope="module")
def sweep():
    f, t, h, truth, sm, sp = physics_sweep([30.0], np.geomspace(0.1, 20, 60), magnitude_std_db=0.2,
                                           phase_std_deg=1.0, seed=5)
    res = RationalFit(4, 4).fit(f, t, h, sm, sp)
    return f, h, truth, res


def test_better_than_levy_and_stable(sweep):
    f, h, truth, res = sweep
    w = 2 * np.pi * f
    wr, g = np.sqrt(w.min() * w.max()), np.exp(np.mean(np.log(np.abs(h))))
    num, den = levy(w / wr, h / g, 4, 4)
    h_levy = g * np.polyval(num[::-1], 1j * w / wr) / np.polyval(den[::-1], 1j * w / wr)
    ours = res.model.frequency_response(f)
    assert relative_rms_error(ours, h) < relative_rms_error(h_levy, h)
    assert np.all(res.model.poles().real < 0)


def test_no_worse_than_aaa(sweep):
    AAA = getattr(pytest.importorskip("scipy.interpolate"), "AAA", None)
    if AAA is None:  # the lowest-versions CI job runs scipy's lower bound
        pytest.skip("scipy.interpolate.AAA arrived in scipy 1.15")

    f, h, truth, res = sweep
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # AAA warns when rtol is not reached
        r = AAA(2j * np.pi * f, h, max_terms=5)  # type (4, 4)
    assert relative_rms_error(res.model.frequency_response(f), h) <= relative_rms_error(r(2j * np.pi * f), h)


def test_no_worse_than_vector_fitting(sweep):
    skrf = pytest.importorskip("skrf")
    from skrf.vectorFitting import VectorFitting

    f, h, truth, res = sweep
    nw = skrf.Network(frequency=skrf.Frequency.from_f(f, unit="hz"), s=h.reshape(-1, 1, 1))
    errs = []
    for n_real in (0, 2, 4):
        vf = VectorFitting(nw)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            vf.vector_fit(n_poles_real=n_real, n_poles_cmplx=(4 - n_real) // 2, init_pole_spacing="log",
                          fit_constant=True, fit_proportional=False, enforce_dc=False)
        errs.append(relative_rms_error(vf.get_model_response(0, 0, freqs=f), h))
    assert relative_rms_error(res.model.frequency_response(f), h) <= min(errs)
