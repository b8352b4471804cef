"""σ of the Welch H1 estimate and its coherence threshold against oracles written here.

The oracles do not use the library's statistics: a Monte-Carlo of circular complex Gaussian
errors (numpy's generator), a brute-force average over angles, ``scipy.stats.f`` quantiles, and
records from a known plant with Gaussian output noise generated below.  In those records each Welch
segment (boxcar, no overlap, no detrending) is one period of the plant's steady state (a circular
convolution per segment), so every bin is exactly ``Y = H U + N``: the setting of the exact results
(Goodman 1957; Bendat & Piersol, *Random Data*, ch. 9).  Leakage is not in σ (module doc of
:mod:`physmodel.estimation.frf`) and is kept out of these records on purpose.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from physmodel.errors import IPMCError
from physmodel.estimation.frf import h1
from physmodel.estimation.frf_estimate import (
    NEPER_TO_DB,
    circle_mean_squares,
    coherence_threshold,
    sigma_exact,
    sigma_from_coherence,
)

N = 64                                   # samples per segment: 32 lines (bins 1..32)


def _records(nd: int, g2: np.ndarray, reps: int, chans: int, seed: int):
    """Welch H1 of ``reps`` inputs (white, ``nd`` segments) × ``chans`` noisy outputs each, on a
    plant whose bin k has |H|² = g2/(1 − g2) against unit noise (expected coherence g2) and a
    phase winding over the band.  Returns the true H per line and the estimates."""
    rng = np.random.default_rng(seed)
    H = np.sqrt(g2 / (1 - g2)) * np.exp(-1j * np.linspace(0, 3 * np.pi, g2.size))
    full = np.concatenate([[1.0], H])                      # DC: any value (h1 drops it)
    ests = []
    for _ in range(reps):
        u = rng.standard_normal((nd, N))
        y = np.fft.irfft(full * np.fft.rfft(u, axis=1), N, axis=1)[None] + rng.standard_normal((chans, nd, N))
        ests.append(h1(1.0, u.ravel(), y.reshape(chans, -1), nperseg=N, noverlap=0, window="boxcar",
                       detrend=False))
    return H, ests


def _g2_grid():
    g2 = np.linspace(0.05, 0.99, N // 2)
    g2[-1] = 0.5                                           # Nyquist bin: real noise, kept at a plain value
    return g2


# ------------------------------------------------------------------------------------- the σ function
@pytest.mark.parametrize("rho", [0.3, 0.9, 1.5, 10.0])
def test_circle_mean_squares_are_the_average_over_angles(rho):
    th = (np.arange(200_000) + 0.5) * (2 * np.pi / 200_000)
    z = 1 - rho * np.exp(1j * th)
    mag, ph = circle_mean_squares(np.array([rho**2]))
    assert mag[0] == pytest.approx(np.mean(np.log(np.abs(z))**2), rel=1e-6)
    assert ph[0] == pytest.approx(np.mean(np.angle(z)**2), rel=1e-4)


@pytest.mark.parametrize("nu", [3.0, 10.0, 25.6])
def test_sigma_exact_is_the_rms_of_the_log_error_of_circular_gaussian_noise(nu):
    """RMS of ln|1 − w| and arg(1 − w), w = r̂ Z, Z circular complex Gaussian, by Monte-Carlo
    (400 000 draws: standard error of an RMS below 0.3 % here)."""
    rng = np.random.default_rng(11)
    g = np.array([0.99, 0.9, 0.5, 0.2, 0.05])
    sm, sp = sigma_exact(g, nu)
    fm, fp = sigma_from_coherence(g, nu)
    for i, gi in enumerate(g):
        r = math.sqrt((1 - gi) / (nu * gi))
        w = r * (rng.standard_normal(400_000) + 1j * rng.standard_normal(400_000)) / math.sqrt(2)
        assert sm[i] == pytest.approx(NEPER_TO_DB * np.sqrt(np.mean(np.log(np.abs(1 - w))**2)), rel=0.01)
        assert sp[i] == pytest.approx(np.degrees(np.sqrt(np.mean(np.angle(1 - w)**2))), rel=0.01)
    # small errors: the first-order (Bendat & Piersol 9.90) σ; at γ² = 0.05 not (8-46 % apart here)
    assert sm[0] == pytest.approx(fm[0], rel=2e-3) and sp[0] == pytest.approx(fp[0], rel=2e-3)
    assert abs(sm[-1] / fm[-1] - 1) > 0.05


def test_sigma_exact_of_zero_coherence_is_infinite_and_shape_is_kept():
    sm, sp = sigma_exact(np.array([[0.0, 0.5], [1.0, 0.9]]), 10.0)
    assert sm.shape == (2, 2) and np.isinf(sm[0, 0]) and np.isinf(sp[0, 0])
    assert sm[1, 0] == 0.0 and np.all(np.isfinite(sm[:, 1]))
    with pytest.raises(IPMCError, match="dof"):
        sigma_exact(np.array([0.5]), 0.0)


# ------------------------------------------------------------------------------------- Welch H1 records
@pytest.mark.parametrize("nd", [4, 8, 32])
def test_exact_confidence_disc_of_welch_h1_covers_at_its_level(nd):
    """Bendat & Piersol's region |H − Ĥ|² ≤ (2/(n − 2)) F_{2,n−2;α} (1 − γ̂²)/γ̂² Ĝ_yy/Ĝ_xx
    (n = 2 nd) is exact for Gaussian output noise: its coverage is 1 − α at every coherence, with
    the estimate's coherence and its degrees of freedom (nd − 1 for boxcar segments without overlap)."""
    g2 = _g2_grid()
    H, ests = _records(nd, g2, reps=10, chans=100, seed=100 + nd)
    nu = nd - 1
    assert ests[0].settings["effective_averages"] == nd
    Hh = np.concatenate([e.response for e in ests])
    coh = np.concatenate([e.coherence for e in ests])
    d2 = np.abs(Hh - H[None])**2
    scale = np.abs(Hh)**2 * (1 - coh) / (nu * coh)       # (1 − γ̂²)/γ̂² Ĝ_yy/Ĝ_xx / ν = |Ĥ|² r̂²
    for alpha in (0.3173, 0.05):
        inside = d2[:, :-1] <= scale[:, :-1] * stats.f.ppf(1 - alpha, 2, 2 * nu)
        n = inside.size
        assert abs(inside.mean() - (1 - alpha)) < 4 * math.sqrt(alpha * (1 - alpha) / n), (alpha, inside.mean())
        low, high = inside[:, :10], inside[:, -11:]                     # at low and at high coherence alike
        for part in (low, high):
            assert abs(part.mean() - (1 - alpha)) < 4 * math.sqrt(alpha * (1 - alpha) / part.size)


@pytest.mark.parametrize("nd", [16, 32])
def test_sigma_of_the_lines_kept_is_calibrated_on_a_known_plant(nd):
    """Lines kept by the estimate's coherence threshold (``significant()``), true coherence spread
    evenly over 0.05-0.99: error/σ of ln|H| and of the phase has RMS within the issue's goal
    (0.7-1.4) and ±2σ covers at least 90 % (with nd ≥ 16, as the front door's Welch segments).
    Measured when written (magnitude/phase): nd = 16: RMS 1.15/1.07, ±2σ 0.92/0.94; nd = 32:
    1.07/1.03, 0.94/0.95.  Not claimed for fewer segments: a line kept because its sample coherence
    came out high also has its |Ĥ| pushed up and its σ down (nd = 8: RMS 1.33/1.18, nd = 4: 1.95/1.70)."""
    g2 = _g2_grid()
    H, ests = _records(nd, g2, reps=20, chans=100, seed=200 + nd)
    keep = np.concatenate([e.significant() for e in ests])[:, :-1]
    d = np.log(np.concatenate([e.response for e in ests]) / H[None])[:, :-1][keep]
    sm = np.concatenate([e.magnitude_std_db for e in ests])[:, :-1][keep] / NEPER_TO_DB
    sp = np.radians(np.concatenate([e.phase_std_deg for e in ests]))[:, :-1][keep]
    for t in (d.real / sm, d.imag / sp):
        assert 0.7 <= np.sqrt(np.mean(t**2)) <= 1.4, np.sqrt(np.mean(t**2))
        assert np.mean(np.abs(t) <= 2) >= 0.90, np.mean(np.abs(t) <= 2)


@pytest.mark.parametrize("nd", [4, 16])
def test_coherence_threshold_of_an_estimate_is_its_false_alarm_probability(nd):
    """Output of pure noise (H = 0): the fraction of estimates with any of their 31 lines above
    the threshold for all lines together is alpha = 1 %; a per-line threshold flags about 27 %."""
    rng = np.random.default_rng(300 + nd)
    hits = per_line = total = 0
    for _ in range(8):
        u = rng.standard_normal(nd * N)
        e = h1(1.0, u, rng.standard_normal((500, nd * N)), nperseg=N, noverlap=0, window="boxcar", detrend=False)
        c = e.coherence[:, :-1]                                        # the Nyquist bin is real, not circular
        thr = coherence_threshold(nd, lines=31)
        hits += int(np.sum(np.any(c >= thr, axis=1)))
        per_line += int(np.sum(np.any(c >= coherence_threshold(nd), axis=1)))
        total += c.shape[0]
    assert abs(hits / total - 0.01) < 4 * math.sqrt(0.01 * 0.99 / total), hits / total
    assert abs(per_line / total - (1 - 0.99**31)) < 4 * math.sqrt(0.27 * 0.73 / total)
    assert e.settings["coherence_lines"] == 32
    assert e.coherence_threshold == pytest.approx(coherence_threshold(nd, lines=32), abs=1e-4)


def test_coherence_threshold_for_many_lines_is_the_sidak_per_line_level():
    assert coherence_threshold(11) == pytest.approx(1 - 0.01**0.1)
    assert coherence_threshold(11, lines=1) == coherence_threshold(11)
    per = 1 - 0.99**(1 / 1000)
    assert coherence_threshold(11, lines=1000) == pytest.approx(1 - per**0.1, rel=1e-12)
    assert coherence_threshold(11, lines=1000) > coherence_threshold(11)
    for bad in (0, 2.5, -3):
        with pytest.raises(IPMCError, match="lines"):
            coherence_threshold(11, lines=bad)
