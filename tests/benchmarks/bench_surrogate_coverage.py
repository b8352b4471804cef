"""Coverage of the scheduled fit's 95 % confidence intervals over many noise draws (a script, not collected by pytest).

    python tests/benchmarks/bench_surrogate_coverage.py                    # seeds 1000-1199
    python tests/benchmarks/bench_surrogate_coverage.py --first-seed 2000 --seeds 100

Why: ``tests/surrogate/test_surrogate_scheduled.py::test_synthetic_scheduled_recovery_within_confidence_intervals``
pools five noise draws (seeds 3-7).  The pooling was added after the single-draw form failed on
seed 3 with the schema-2 zpk parametrisation (4 of 18 coefficients outside their intervals), so
that test is not, by itself, evidence that the intervals are honest.  This benchmark is: it fits
the same known scheduled model on fresh noise draws the test never saw and counts how often each
95 % interval holds the true coefficient.

The truth is evaluated here, independently of ``surrogate``'s own evaluation code, from the model's
definition (``surrogate/_structure.py``'s docstring): with s̃ = jω/ω_ref and τ = (T − 37 °C)/18 °C,

    H = g_ref · k(τ) · (1 + β1(τ) s̃ + β2(τ) s̃²) / ((s̃² + e^{l1(τ)} s̃ + e^{l0(τ)}) (s̃ + e^{lc(τ)}))

every slot a quadratic in τ (coefficients ascending), the rows of ``TRUE_THETA`` in that order.
It is checked against ``RationalModel.frequency_response`` once (relative difference printed).
Noise: 0.1 dB and 0.6° Gaussian on log-magnitude and phase, 7 temperatures 19-55 °C, 40 lines
0.1-30 Hz — the test's design, drawn here with numpy's generator from each seed.

Printed: convergence, the pooled coverage of all coefficients' intervals (Wilson 95 %), the
coverage per coefficient (min and max over the 18), the RMS of (θ̂ − θ)/σ̂ (1 for honest standard
errors), and how many draws have ≥ 4 of 18 outside — the event of seed 3.  For 18 independent
coefficients at 95 % that last figure would be about 1 %; the coefficients are correlated, which
widens it.

Measured 2026-11-26 (seeds 1000-1199, never used by the tests or to set anything; the first command):

    independent truth vs RationalModel: max relative difference 7.4e-16
    draws: 200, converged 200
    pooled coverage of the 95 % intervals: 3400/3600 = 94 % (95 %: 94-95 %)
    per coefficient: min 0.900 (index 16: log_c's linear term), max 0.985
    RMS of (estimate - truth)/stderr: 1.023 (per coefficient 0.95-1.14)
    draws with >= 4 of 18 outside: 11/200 = 6 % (95 %: 3-10 %)

What that says, and what it does not:

* Pooled over the 18 coefficients the coverage is 94.4 % for a nominal 95 %.  The pooled Wilson
  interval treats 3600 indicators as independent; the 18 of one draw are correlated, so the true
  uncertainty of that figure is wider than printed.
* One coefficient is under-covered: log_c's linear term (index 16) holds its truth in 180/200
  draws, 90 % (Wilson 95 %: 85-93 %, which excludes 95 %; p ≈ 0.003 for that coefficient, ≈ 0.05
  family-wise over 18).  Its RMS standardised error is 1.14: its standard error is about 14 % too
  small (a linearised covariance of a log-parametrised pole in a nonlinear fit).  Not corrected
  here; the test's pooled-draw check would not see it.
* Seed 3's draw (4 of 18 outside) is an event of about 6 % of draws, not by itself a sign of
  narrow intervals.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

sys.path.append(os.path.join(os.path.dirname(__file__), "..", "surrogate"))
sys.path.insert(0, os.path.dirname(__file__))

from _stats import wilson_text  # noqa: E402
from surrogate_fixtures import FIT_TEMPS, TRUE_SCALING, TRUE_THETA  # noqa: E402

from surrogate import RationalModel, ScheduledFit, Structure  # noqa: E402

F_LINES = np.geomspace(0.1, 30, 40)
MAG_DB, PH_DEG = 0.1, 0.6


def truth(f_hz: np.ndarray, t_c: np.ndarray) -> np.ndarray:
    """The known model's response, evaluated from its definition (not with surrogate's code)."""
    rows = TRUE_THETA.reshape(6, 3)
    tau = (t_c - TRUE_SCALING.temperature_center_c) / TRUE_SCALING.temperature_scale_c
    k, b1, b2, l1, l0, lc = (r[0] + r[1] * tau + r[2] * tau ** 2 for r in rows)
    s = 1j * 2 * np.pi * f_hz / TRUE_SCALING.omega_ref_rad_s
    return TRUE_SCALING.gain_ref * k * (1 + b1 * s + b2 * s * s) / ((s * s + np.exp(l1) * s + np.exp(l0)) * (s + np.exp(lc)))


def draw(seed: int):
    f = np.tile(F_LINES, len(FIT_TEMPS))
    t = np.repeat(np.asarray(FIT_TEMPS, float), F_LINES.size)
    rng = np.random.default_rng(seed)
    ln_mag = rng.normal(size=f.size) * MAG_DB * np.log(10) / 20
    ph = np.deg2rad(rng.normal(size=f.size) * PH_DEG)
    h = truth(f, t) * np.exp(ln_mag + 1j * ph)
    return f, t, h, np.full(f.size, MAG_DB), np.full(f.size, PH_DEG)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first-seed", type=int, default=1000)
    ap.add_argument("--seeds", type=int, default=200)
    a = ap.parse_args(argv)

    f, t, _, _, _ = draw(0)
    ref = RationalModel(Structure("zpk", 2, 3, 2), TRUE_THETA, TRUE_SCALING, (19.0, 55.0)).frequency_response(f, t)
    print(f"independent truth vs RationalModel: max relative difference {np.max(np.abs(truth(f, t) / ref - 1)):.1e}")

    scales = dict(omega_ref_rad_s=TRUE_SCALING.omega_ref_rad_s, gain_ref=TRUE_SCALING.gain_ref,
                  temperature_center_c=TRUE_SCALING.temperature_center_c,
                  temperature_scale_c=TRUE_SCALING.temperature_scale_c)
    inside, z, bad4, conv, wrms = [], [], 0, 0, []
    seeds = range(a.first_seed, a.first_seed + a.seeds)
    for seed in seeds:
        res = ScheduledFit("zpk", 2, 3, 2, **scales).fit(*draw(seed))
        if not (res.converged and res.method == "joint"):
            print(f"seed {seed}: not converged ({res.status}); left out of the coverage")
            continue
        conv += 1
        ins = (TRUE_THETA >= res.ci95_low) & (TRUE_THETA <= res.ci95_high)
        inside.append(ins)
        z.append((res.params - TRUE_THETA) / res.stderr)
        wrms.append(res.weighted_rms)
        bad4 += int(np.sum(~ins) >= 4)
    inside_a, z_a = np.array(inside), np.array(z)
    n = inside_a.size
    print(f"draws: {len(seeds)}, converged {conv}")
    print(f"pooled coverage of the 95 % intervals: {wilson_text(int(inside_a.sum()), n)}")
    per = inside_a.mean(axis=0)
    print(f"per coefficient: min {per.min():.3f} (index {int(per.argmin())}), max {per.max():.3f}")
    print(f"RMS of (estimate - truth)/stderr: {np.sqrt(np.mean(z_a ** 2)):.3f} "
          f"(per coefficient {np.sqrt(np.mean(z_a ** 2, axis=0)).min():.2f}-{np.sqrt(np.mean(z_a ** 2, axis=0)).max():.2f})")
    print(f"weighted residual RMS: median {np.median(wrms):.3f}")
    print(f"draws with >= 4 of 18 outside: {wilson_text(bad4, conv)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
