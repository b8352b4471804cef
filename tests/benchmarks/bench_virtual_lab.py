"""Benchmark of the virtual lab (issue 15; not collected by pytest): the whole chain

    multisine design → physics time records at 8 bath temperatures (seed 001 actuator, a perturbed
    "true" strip) with laser noise and 16-bit quantisation → H1 FRF with per-line σ → calibration
    (free d, alpha0, E; starts from the published set) → temperature-scheduled zpk surrogate fitted
    without the held-out 35/45 °C → stable-inversion feedforward (preview 'inf') at held-out 45 °C
    → the voltage applied to the true physics plant (timesim) → tracking error against the
    steady-state prediction A·|P(jω)/G(jω) − 1| from the true physics frequency response,

the demo's settings (scenarios/demo.toml) except where the data come from.  Each stage prints its
error against an oracle it did not produce (the true physics, the simulated parameter values) and
its wall time.  The same surrogate and inversion stages are then run on the demo's own kind of
data (the physics response plus 0.2 dB / 1° magnitude/phase noise) for comparison.  Finally a
Monte Carlo of the calibration over ``--draws`` noise draws gives the coverage of its 95 %
intervals (σ estimated with ν = 2(P − 1) degrees of freedom; the expected coverage printed).

``--demo`` also runs the flagship scenario (scenarios/demo.toml) with its data from the virtual
lab, through the runner hook proposed for ``[sweep] source = "virtual_lab"`` (installed here by
replacing the runner's sweep step in this process only; runner.py is not changed) and prints its
checks.

    python tests/benchmarks/bench_virtual_lab.py [--draws 200] [--periods 8] [--oversample 8] [--demo]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from physmodel import ActuatorModel, get_parameter_set
from physmodel.data.excitation import multisine, settle_time_s
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from physmodel.data.timesim import model_realization, simulate, time_grid
from physmodel.estimation.calibration import calibrate
from scenarios.virtual_lab import Measurement, virtual_lab

TEMPS = [19.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0]
HELD = [35.0, 45.0]
FREE = ("d", "alpha0", "E")
FS, PERIOD = 500.0, 10.0
LN = math.log(10.0) / 20.0


def setup():
    base = get_parameter_set("seed001_actuator")
    truth = base.replace(d=base.d * 1.4, alpha0=base.alpha0 * 0.8, E=base.E * 1.15, name="virtual_strip")
    f = np.unique(np.round(np.geomspace(0.1, 9.0, 30) * PERIOD)) / PERIOD
    ms = multisine(f, FS, PERIOD, rms=1.0)
    meas = lambda seed: Measurement(output_noise_rms=20e-6, output_adc_step=10e-3 / 2**16,
                                    input_adc_step=20.0 / 2**16, seed=seed)
    return base, truth, f, ms, meas


def stage_surrogate_and_inversion(data, truth_model, label, **fit_kw):
    from inversion import feedforward
    from surrogate import fit_sweep, relative_rms_error

    t0 = time.perf_counter()
    fit = fit_sweep(data.exclude(HELD), 4, 4, 2, form="zpk", method="joint", raise_on_failure=False, **fit_kw)
    t_fit = time.perf_counter() - t0
    exact = synthesize_sweep(truth_model, "M", np.unique(data.frequency_hz), TEMPS)
    held = [relative_rms_error(fit.model.frequency_response(exact.select(T).frequency_hz, T, extrapolate=True),
                               exact.select(T).response) for T in HELD]
    print(f"  [{label}] surrogate zpk 4/4 degree 2, joint on {len(TEMPS) - len(HELD)} temperatures: converged="
          f"{fit.converged}, held-out rel. RMS vs true physics {', '.join(f'{T:g} °C {e:.4f}' for T, e in zip(HELD, held))}"
          f" ({t_fit:.2f} s)")
    # demo.toml [inversion]: 8 kHz, 12 s, error window 6-11.5 s, lead 1 s, raised-cosine ramp 2 s
    fs, dur, A, fr, T = 8000.0, 12.0, 0.65, 2.0, 45.0
    t = time_grid(dur, fs)
    tau = t - 1.0
    env = np.where(tau < 0, 0.0, np.where(tau < 2.0, 0.5 * (1 - np.cos(np.pi * tau / 2.0)), 1.0))
    ref = env * A * np.sin(2 * np.pi * fr * tau)
    G = fit.model.at(T, extrapolate=True)
    t0 = time.perf_counter()
    u = feedforward(G, t, ref, preview="inf", limits="off").output   # as demo.toml: a virtual plant, > 3 V
    t_inv = time.perf_counter() - t0
    t0 = time.perf_counter()
    got = simulate(truth_model, T, t, u).output * 1e3
    t_sim = time.perf_counter() - t0
    win = (t >= 6.0) & (t <= t[-1] - 0.5)
    emax = float(np.max(np.abs(got - ref)[win]))
    P = truth_model.frequency_response([fr], [T])["M"][0, 0, 0] * 1e3
    pred = A * abs(P / complex(G(2j * np.pi * fr)) - 1)
    print(f"  [{label}] feedforward 2 Hz, {A} mm at {T:g} °C on the true plant: max |error| {emax:.5f} mm "
          f"({emax / A:.2%}), steady-state prediction A|P/G − 1| = {pred:.5f} mm, ratio {emax / pred:.3f} "
          f"(inversion {t_inv:.2f} s, plant simulation {t_sim:.2f} s)")
    return fit


def chain(periods: int, oversample: int):
    base, truth, f, ms, meas = setup()
    tm = ActuatorModel(truth)
    real = model_realization(tm, TEMPS[0], FS, 100.0)
    settle = settle_time_s(real.poles, 1e-6)
    tp = math.ceil(settle / PERIOD)
    print(f"== whole chain: seed 001 actuator with d×1.4, alpha0×0.8, E×1.15 (the truth); {len(TEMPS)} temperatures; "
          f"multisine {f.size} lines {f[0]:g}-{f[-1]:g} Hz, period {PERIOD:g} s at {FS:g} Hz, crest factor "
          f"{ms.crest_factor:.2f}; {tp} transient period(s) (slowest pole settles to 1e-6 in {settle:.1f} s) + "
          f"{periods} measured; laser 20 µm RMS, 16-bit ADCs (±10 V, ±5 mm); simulation oversampled ×{oversample}")
    t0 = time.perf_counter()
    r = virtual_lab(tm, ms, TEMPS, meas(2026), periods=periods, transient_periods=tp, oversample=oversample,
                    max_std_db=1.0)
    t_lab = time.perf_counter() - t0
    ex = synthesize_sweep(tm, "M", r.sweep.frequency_hz[r.sweep.temperature_c == TEMPS[0]], TEMPS)
    d = np.log(r.sweep.response / ex.response)
    tt = np.concatenate([d.real / (r.sweep.magnitude_std_db * LN), d.imag / np.radians(r.sweep.phase_std_deg)])
    nu = 2 * (periods - 1)
    print(f"  virtual lab: {r.sweep.frequency_hz.size} lines kept of {f.size * len(TEMPS)}; {r.duration_s:g} s of "
          f"measurement per temperature ({r.duration_s * len(TEMPS) / 60:.1f} min in the lab); wall {t_lab:.2f} s = "
          + ", ".join(f"{k} {v:.2f} s" for k, v in r.timings_s.items()))
    print(f"  FRF vs true physics: median σ {np.median(r.sweep.magnitude_std_db):.4f} dB / "
          f"{np.median(r.sweep.phase_std_deg):.4f}°; max |error| {np.max(np.abs(20 * np.log10(np.abs(r.sweep.response / ex.response)))):.4f} dB; "
          f"mean t² {np.mean(tt**2):.3f} (t_{nu}: {nu / (nu - 2):.3f}); |t| ≤ 2 for {np.mean(np.abs(tt) <= 2):.3f} "
          f"(t_{nu}: {stats.t.cdf(2, nu) - stats.t.cdf(-2, nu):.3f})")
    t0 = time.perf_counter()
    res = calibrate(r.sweep, base, list(FREE), starts=4, seed=0)
    t_cal = time.perf_counter() - t0
    print(f"  calibration from the published set ({t_cal:.2f} s, converged={res.converged}, cost {res.cost:.1f}, "
          f"Gaussian expectation {res.expected_cost:.1f}, Student-t {0.5 * (2 * res.n_lines - 3) * nu / (nu - 2):.1f}):")
    for n in FREE:
        true = getattr(truth, n)
        print(f"    {n:7s} true {true:.5g}  estimate {res.values[n]:.5g}  rel. error {res.values[n] / true - 1:+.2e}  "
              f"95 % [{res.ci_lower[n]:.5g}, {res.ci_upper[n]:.5g}]  inside {res.ci_lower[n] <= true <= res.ci_upper[n]}  "
              f"(start {getattr(base, n):.5g})")
    cal_model = ActuatorModel(res.parameters)
    fd = np.geomspace(0.1, 9.0, 200)
    dev = np.abs(cal_model.frequency_response(fd, TEMPS)["M"][0] / tm.frequency_response(fd, TEMPS)["M"][0] - 1)
    print(f"  calibrated physics vs true physics, 0.1-9 Hz, all temperatures: max relative error {dev.max():.2e}")
    stage_surrogate_and_inversion(r.sweep, tm, "virtual lab, weighted by its σ")
    stage_surrogate_and_inversion(r.sweep, tm, "virtual lab, log weighting", weighting="log")
    demo = synthesize_sweep(tm, "M", f, TEMPS, MagnitudePhaseNoise(0.2, 1.0), seed=2)
    stage_surrogate_and_inversion(demo, tm, "demo-style 0.2 dB/1° noise")
    return tp


def coverage(draws: int, periods: int, tp: int, oversample: int):
    base, truth, _f, ms, meas = setup()
    tm = ActuatorModel(truth)
    temps = [25.0, 45.0]
    nu = 2 * (periods - 1)
    inside, z, t_all = [], [], time.perf_counter()
    for k in range(draws):
        r = virtual_lab(tm, ms, temps, meas(10_000 + k), periods=periods, transient_periods=tp, oversample=oversample,
                        max_std_db=1.0)
        res = calibrate(r.sweep, base, list(FREE), starts=2, seed=0)
        inside.append([res.ci_lower[n] <= getattr(truth, n) <= res.ci_upper[n] for n in FREE])
        z.append([(res.values[n] - getattr(truth, n)) / res.stderr[n] for n in FREE])
    inside, z = np.array(inside), np.array(z)
    # σ̂ with ν dof used as known weights: one dominant line gives z ~ t_ν (sd sqrt(ν/(ν−2)));
    # many comparable lines give E z² = E[c²]/E[c] = ν/(ν−4) with c = σ²/σ̂² ~ ν/χ²_ν
    lo_sd, hi_sd = math.sqrt(nu / (nu - 2)), math.sqrt(nu / (nu - 4))
    cov = lambda sd: 2 * stats.norm.cdf(1.96 / sd) - 1
    band = 1.96 * math.sqrt(0.9 * 0.1 / draws)
    print(f"== calibration coverage over {draws} draws (2 temperatures, {periods} periods; {time.perf_counter() - t_all:.1f} s)")
    print(f"  expected with σ estimated on ν = {nu}: between {cov(hi_sd):.3f} and {cov(lo_sd):.3f} (±{band:.3f} "
          f"binomial 95 %); nominal 0.95")
    for i, n in enumerate(FREE):
        print(f"  {n:7s} coverage {inside[:, i].mean():.3f}; standardised error mean {z[:, i].mean():+.3f}, "
              f"sd {z[:, i].std(ddof=1):.3f} (expected {lo_sd:.3f}-{hi_sd:.3f})")


def demo():
    import tempfile

    from scenarios import runner
    from scenarios.demo import DEMO_SCENARIO
    from scenarios.spec import load_scenario

    spec = load_scenario(DEMO_SCENARIO)          # its [sweep] source is the virtual lab
    with tempfile.TemporaryDirectory() as out:
        res = runner.run_scenario(spec, out, quiet=True)
        print("== flagship demo with its sweep from the virtual lab (seed001_actuator, 20 µm laser noise, 16-bit ADCs)")
        print("  " + runner.summary_line(res))
        for c in res.checks:
            print(f"  {c.name:20s} {'PASS' if c.passed else 'FAIL'} {c.value:.4g} ({c.bound_text()})")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--periods", type=int, default=8)
    ap.add_argument("--oversample", type=int, default=8)
    ap.add_argument("--demo", action="store_true", help="also run the flagship scenario on virtual-lab data")
    a = ap.parse_args()
    if a.demo:
        demo()
    tp = chain(a.periods, a.oversample)
    if a.draws > 0:
        coverage(a.draws, a.periods, tp, a.oversample)


if __name__ == "__main__":
    main()
