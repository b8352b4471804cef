"""Benchmark of the calibration engine (not collected by pytest):

1. an 8-parameter calibration on 10 temperatures × 50 frequencies (seed002_table3 geometry, a
   perturbed truth, magnitude/phase noise 0.1 dB / 1°): wall time, model evaluations, recovered
   vs true values with their 95 % intervals;
2. a Monte Carlo check of the intervals: the same calibration over N noise draws (default 400),
   coverage of the nominal 95 % intervals per parameter (with the binomial 95 % band of the
   coverage estimate), mean cost against its expectation F − nθ/2;
3. the same coverage check on sweeps without per-line std, where the noise level is estimated.

    python3 tests/benchmarks/bench_calibration.py [--draws 400] [--starts 4]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from physmodel import ActuatorModel, get_parameter_set  # noqa: E402
from physmodel.data.sweep import (
    ComplexGaussianNoise,
    MagnitudePhaseNoise,
    synthesize_sweep,  # noqa: E402
)
from physmodel.estimation.calibration import calibrate  # noqa: E402
from physmodel.temperature import Arrhenius, LogLinear  # noqa: E402

FREE = ["d", "kappa_e", "alpha0", "E", "xi", "r1_sheet", "laws.d.activation_energy", "laws.E.slope"]
TEMPS = np.linspace(5.0, 75.0, 10)
FREQS = np.logspace(-1, 2, 50)
NOISE = MagnitudePhaseNoise(0.1, 1.0)


def setup():
    base = get_parameter_set("seed002_table3")
    truth = replace(base.replace(d=4.2e-11, kappa_e=3.9e-7, alpha0=base.alpha0 * 1.15, E=1.7e8, xi=0.21,
                                 r1_sheet=80.0),
                    laws=base.laws.with_(d=Arrhenius(19e3), E=LogLinear(-0.009)))
    true = {"d": truth.d, "kappa_e": truth.kappa_e, "alpha0": truth.alpha0, "E": truth.E, "xi": truth.xi,
            "r1_sheet": truth.r1_sheet, "laws.d.activation_energy": 19e3, "laws.E.slope": -0.009}
    return base, truth, true


def single(base, truth, true, starts):
    sw = synthesize_sweep(ActuatorModel(truth), "M", FREQS, TEMPS, noise=NOISE, seed=2026)
    t0 = time.perf_counter()
    res = calibrate(sw, base, FREE, starts=starts, seed=0)
    dt = time.perf_counter() - t0
    print(f"== 8-parameter calibration: {len(TEMPS)} temperatures x {len(FREQS)} frequencies "
          f"({res.n_lines} lines), {starts} starts")
    print(f"time {dt:.2f} s; {res.n_evaluations} model evaluations (parameter sets x all lines) "
          f"in {res.n_model_calls} batched calls; converged={res.converged}")
    print(f"cost {res.cost:.1f}, expected {res.expected_cost:.1f} +- {res.cost_std:.1f}; held: {res.held or 'none'}")
    print(f"{'parameter':28s} {'true':>12s} {'estimate':>12s} {'95 % interval':>28s}  inside")
    for n in FREE:
        inside = res.ci_lower[n] <= true[n] <= res.ci_upper[n]
        print(f"{n:28s} {true[n]:12.5g} {res.values[n]:12.5g} [{res.ci_lower[n]:12.5g}, {res.ci_upper[n]:12.5g}]  "
              f"{'yes' if inside else 'NO'}")
    for s in res.starts:
        print(f"  start {s.index}: cost {s.cost:.1f} after {s.nfev} residual evaluations ({s.message})")
    return res


def monte_carlo(base, truth, true, draws):
    exact = ActuatorModel(truth)
    hits = {n: 0 for n in FREE}
    costs, expected, held, failed = [], [], 0, 0
    evals = []
    t0 = time.perf_counter()
    try:
        from tqdm import tqdm
        it = tqdm(range(draws), desc="monte carlo", file=sys.stderr)
    except ImportError:  # pragma: no cover
        it = range(draws)
    for k in it:
        sw = synthesize_sweep(exact, "M", FREQS, TEMPS, noise=NOISE, seed=10_000 + k)
        res = calibrate(sw, base, FREE, starts=1)
        if not res.converged:
            failed += 1
        held += bool(res.held)
        costs.append(res.cost)
        expected.append(res.expected_cost)
        evals.append(res.n_evaluations)
        for n in FREE:
            if n not in res.held and res.ci_lower[n] <= true[n] <= res.ci_upper[n]:
                hits[n] += 1
    dt = time.perf_counter() - t0
    half = 1.96 * math.sqrt(0.95 * 0.05 / draws)
    print(f"\n== Monte Carlo coverage of the 95 % intervals over {draws} noise draws ({dt:.1f} s, "
          f"{np.mean(evals):.0f} model evaluations per calibration)")
    print(f"not converged: {failed}; draws with a parameter held as undetermined: {held}")
    print(f"mean cost {np.mean(costs):.1f} (expected {np.mean(expected):.1f}); "
          f"sd {np.std(costs, ddof=1):.1f} (expected {math.sqrt(np.mean(expected)):.1f})")
    print(f"coverage (nominal 0.95; a correct interval lands in [{0.95 - half:.3f}, {0.95 + half:.3f}] "
          f"95 % of the time at this N):")
    for n in FREE:
        print(f"  {n:28s} {hits[n] / draws:.3f}")
    print(f"  {'all parameters (mean)':28s} {np.mean([hits[n] / draws for n in FREE]):.3f}")


def monte_carlo_estimated_noise(base, truth, true, draws):
    """Sweeps without per-line std (complex noise 1 %): intervals rely on the estimated noise level."""
    exact = ActuatorModel(truth)
    hits = {n: 0 for n in FREE}
    scales = []
    t0 = time.perf_counter()
    for k in range(draws):
        sw = synthesize_sweep(exact, "M", FREQS, TEMPS, noise=ComplexGaussianNoise(0.01), seed=20_000 + k)
        sw = replace(sw, magnitude_std_db=None, phase_std_deg=None)
        res = calibrate(sw, base, FREE, starts=1)
        scales.append(res.noise_scale)
        for n in FREE:
            if n not in res.held and res.ci_lower[n] <= true[n] <= res.ci_upper[n]:
                hits[n] += 1
    half = 1.96 * math.sqrt(0.95 * 0.05 / draws)
    print(f"\n== Same, data WITHOUT per-line std (complex noise 1 %, noise estimated), {draws} draws "
          f"({time.perf_counter() - t0:.1f} s)")
    print(f"estimated noise scale {np.mean(scales):.4f} (true {0.01 / math.sqrt(2) / 0.01:.4f}); "
          f"coverage band for N={draws}: [{0.95 - half:.3f}, {0.95 + half:.3f}]")
    print("  " + ", ".join(f"{n} {hits[n] / draws:.3f}" for n in FREE))
    print(f"  all parameters (mean) {np.mean([hits[n] / draws for n in FREE]):.3f}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--draws", type=int, default=400)
    ap.add_argument("--starts", type=int, default=4)
    ap.add_argument("--draws-estimated", type=int, default=200,
                    help="draws of the estimated-noise coverage check (0 to skip)")
    args = ap.parse_args(argv)
    base, truth, true = setup()
    single(base, truth, true, args.starts)
    monte_carlo(base, truth, true, args.draws)
    if args.draws_estimated:
        monte_carlo_estimated_noise(base, truth, true, args.draws_estimated)


if __name__ == "__main__":
    main()
