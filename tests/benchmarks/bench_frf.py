"""Benchmark of FRF estimation (issue 15; not collected by pytest):

1. σ calibration over N noise draws (default 200): coverage of ±2σ of ln|H| and of the phase, and
   the mean squared standardised error (χ²/term), for
   * H1, white input, output noise, Hann 50 % overlap and Hann without overlap;
   * H2, white input, input noise;
   * stepped sine, 20 steps × 20 periods, noise on input and output;
   against python-control plants discretised exactly (tests/estimation/frf_oracle.py).  Lines
   are split by true coherence: the first-order σ is claimed for γ² ≥ 0.2 only.  With ν degrees
   of freedom behind each σ the expected ±2σ coverage is P(|t_ν| < 2), printed alongside.
2. The naive ratio of whole-record FFTs Y/U on the same records against H1: its actual scatter
   (it has no σ) against H1's actual scatter and H1's stated σ.
3. Time and peak memory of H1 and of a stepped sine on a 10-minute, 10 kHz record of three
   channels (voltage, current, displacement) plus its time column, generated block by block into a
   memory-mapped .npy in a temporary folder and read in blocks; a record a third as long for
   comparison shows the peak does not grow with the record (it is set by ``block_samples``).

    python tests/benchmarks/bench_frf.py [--draws 200] [--minutes 10] [--fs 10000]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
from scipy import signal, stats

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "estimation"))

import frf_oracle as orc  # noqa: E402

from physmodel.data.excitation import stepped_sine_plan  # noqa: E402
from physmodel.estimation.frf import h1, h2  # noqa: E402
from physmodel.estimation.stepped import stepped_sine  # noqa: E402

LN = math.log(10.0) / 20.0
FS = 1000.0


def t_coverage(nu: float) -> float:
    return float(stats.t.cdf(2, nu) - stats.t.cdf(-2, nu))


def standardised(est, H_true):
    d = np.log(est.response[0] / H_true)
    return d.real / (est.magnitude_std_db[0] * LN), d.imag / np.radians(est.phase_std_deg[0])


def report(name, tm, tp, nu, draws):
    n = tm.size
    band = 1.96 * math.sqrt(0.95 * 0.05 / n)
    cm, cp = np.mean(np.abs(tm) <= 2), np.mean(np.abs(tp) <= 2)
    print(f"  {name:34s} lines {n:7d}  coverage mag {cm:.4f} phase {cp:.4f}  (t_{nu:.0f}: {t_coverage(nu):.4f}, "
          f"±{band:.4f} binomial)  χ²/term mag {np.mean(tm**2):.3f} phase {np.mean(tp**2):.3f} "
          f"(expected {nu / (nu - 2):.3f})  robust sd (1.4826·MAD) mag {1.4826 * np.median(np.abs(tm)):.3f} "
          f"phase {1.4826 * np.median(np.abs(tp)):.3f}")


def welch_coverage(draws: int):
    print(f"== 1. σ calibration over {draws} draws (python-control resonance 50 Hz, ζ = 0.2, fs = 1 kHz)")
    sysd = orc.resonant(FS)
    n = 102_400
    cases = [("H1 hann 50% (output noise 0.3)", h1, dict(nperseg=1024), dict(output_noise=0.3), "out"),
             ("H1 hann no overlap (output noise 0.3)", h1, dict(nperseg=1024, noverlap=0), dict(output_noise=0.3), "out"),
             ("H2 hann 50% (input noise 0.3)", h2, dict(nperseg=1024), dict(input_noise=0.3), "in")]
    naive = {"h1_db": [], "h1_deg": [], "naive_db": [], "naive_deg": [], "sig_db": [], "sig_deg": [], "gamma2": []}
    for name, fn, kw, noise, where in cases:
        tms, tps, gs, sds = [], [], [], []
        t0 = time.perf_counter()
        for d in range(draws):
            u, y, _, _ = orc.white_record(sysd, n, seed=10_000 + d, **noise)
            e = fn(FS, u, y, **kw)
            H = orc.truth(sysd, e.frequency_hz, FS)
            tm, tp = standardised(e, H)
            tms.append(tm)
            tps.append(tp)
            sds.append(e.magnitude_std_db[0])
            s2 = noise.get("output_noise", 0.0)**2 if where == "out" else noise["input_noise"]**2
            gs.append(np.abs(H)**2 / (np.abs(H)**2 + s2) if where == "out" else np.full(H.size, 1 / (1 + s2)))
            if fn is h1 and "noverlap" not in kw:
                k = np.arange(1, e.frequency_hz.size + 1) * (n // 1024)
                Hn = np.fft.rfft(y)[k] / np.fft.rfft(u)[k]
                dn, dh = np.log(Hn / H), np.log(e.response[0] / H)
                naive["naive_db"].append(dn.real / LN)
                naive["naive_deg"].append(np.degrees(dn.imag))
                naive["h1_db"].append(dh.real / LN)
                naive["h1_deg"].append(np.degrees(dh.imag))
                naive["sig_db"].append(e.magnitude_std_db[0])
                naive["sig_deg"].append(e.phase_std_deg[0])
                naive["gamma2"].append(gs[-1])
        dt = time.perf_counter() - t0
        tm, tp, g = np.concatenate(tms), np.concatenate(tps), np.concatenate(gs)
        nu = 2 * (e.settings["effective_averages"] - 1)
        print(f" {name}: {e.settings['segments']} segments, {e.settings['effective_averages']:.1f} effective; "
              f"{dt / draws * 1e3:.1f} ms per draw (simulation included)")
        for lo, hi in ((0.9, 1.01), (0.5, 0.9), (0.2, 0.5), (0.02, 0.2), (0.0, 0.02)):
            m = (g >= lo) & (g < hi)
            if m.any():
                report(f"true γ² in [{lo:g}, {min(hi, 1):g})", tm[m], tp[m], nu, draws)
        m = g >= 0.2
        report("all lines with γ² ≥ 0.2", tm[m], tp[m], nu, draws)
        sd = np.concatenate(sds)
        for lo, hi in ((0.0, 0.5), (0.5, 1.0), (1.0, 2.0), (2.0, 4.0), (4.0, np.inf)):
            m = (sd >= lo) & (sd < hi)
            if m.any():
                report(f"stated σ in [{lo:g}, {hi:g}) dB", tm[m], tp[m], nu, draws)
    return {k: np.concatenate(v) for k, v in naive.items()}


def stepped_coverage(draws: int):
    sysd = orc.resonant(FS)
    f = np.geomspace(1.0, 200.0, 20)
    P = 20
    plan = stepped_sine_plan(f, FS, periods=P, settle_s=0.2)
    t, u0, y0 = orc.stepped_record(sysd, plan.frequency_hz, plan.step_start_s, plan.step_stop_s, FS)
    H = orc.truth(sysd, f, FS)
    tms, tps = [], []
    t0 = time.perf_counter()
    for d in range(draws):
        rng = np.random.default_rng(20_000 + d)
        e = stepped_sine(t, u0 + 0.002 * rng.standard_normal(u0.size), y0 + 0.05 * rng.standard_normal(u0.size),
                         plan=plan)
        tm, tp = standardised(e, H)
        tms.append(tm)
        tps.append(tp)
    dt = time.perf_counter() - t0
    print(f" stepped sine: {f.size} steps × {P} periods, {plan.duration_s:.1f} s record; {dt / draws * 1e3:.1f} ms per draw")
    report("stepped sine, all steps", np.concatenate(tms), np.concatenate(tps), P - 1, draws)


def naive_comparison(nv):
    print("== 2. naive whole-record FFT ratio Y/U vs H1 (H1 hann 50 % records above, at H1's lines)")
    for sel, label in ((nv["gamma2"] >= 0.2, "true γ² ≥ 0.2"), (nv["gamma2"] >= 0.0, "all lines")):
        print(f"  {label} ({sel.sum()} lines):")
        for key, unit in (("db", "dB"), ("deg", "deg")):
            a, b = np.abs(nv[f"naive_{key}"][sel]), np.abs(nv[f"h1_{key}"][sel])
            print(f"    |error| [{unit}]  naive: median {np.median(a):.3f}  95 % {np.percentile(a, 95):.3f}  "
                  f"rms {np.sqrt(np.mean(a**2)):.3f}  |  H1: median {np.median(b):.3f}  95 % {np.percentile(b, 95):.3f}  "
                  f"rms {np.sqrt(np.mean(b**2)):.3f}, stated σ rms {np.sqrt(np.mean(nv[f'sig_{key}'][sel]**2)):.3f} "
                  f"(the naive ratio states no σ)")


# ----------------------------------------------------------------------------------- big record
def write_record(path: Path, minutes: float, fs: float, kind: str, block: int = 1 << 20):
    """(4, n) float64 .npy memmap: time, voltage [V], current [A], displacement [mm]; block by block."""
    n = int(minutes * 60 * fs)
    plan = None
    if kind == "stepped":                 # 30 steps of about minutes/30 each, 0.5 s settle
        plan = stepped_sine_plan(np.geomspace(0.5, 500, 30), fs, periods=10, min_measure_s=minutes * 2 - 0.5,
                                 settle_s=0.5)
        n = plan.n_samples
    adm = orc.coefficients(orc.resonant(fs, f_n=300.0, zeta=0.7, gain=0.02))
    mob = orc.coefficients(orc.resonant(fs, f_n=40.0, zeta=0.3, gain=2.0))
    arr = np.lib.format.open_memmap(path, mode="w+", dtype=np.float64, shape=(4, n))
    zi_a = np.zeros(max(len(adm[1]), len(adm[0])) - 1)
    zi_m = np.zeros(max(len(mob[1]), len(mob[0])) - 1)
    rng = np.random.default_rng(1)
    for a in range(0, arr.shape[1], block):
        b = min(arr.shape[1], a + block)
        t = np.arange(a, b) / fs
        if plan is None:
            v = rng.standard_normal(b - a)
        else:
            i = np.clip(np.searchsorted(plan.step_start_s, t + 0.5 / fs, side="right") - 1, 0, None)
            v = np.sin(2 * np.pi * plan.frequency_hz[i] * (t - plan.step_start_s[i]))
        cur, zi_a = signal.lfilter(*adm, v, zi=zi_a)
        disp, zi_m = signal.lfilter(*mob, v, zi=zi_m)
        arr[0, a:b] = t
        arr[1, a:b] = v + 1e-3 * rng.standard_normal(b - a)
        arr[2, a:b] = cur + 1e-4 * rng.standard_normal(b - a)
        arr[3, a:b] = disp + 0.02 * rng.standard_normal(b - a)
    arr.flush()
    del arr
    return plan


def timed(fn):
    tracemalloc.start()
    t0 = time.perf_counter()
    out = fn()
    dt = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return out, dt, peak


def big_record(minutes: float, fs: float):
    print(f"== 3. {minutes:g}-minute {fs:g} Hz record: time, voltage, current, displacement (memory-mapped .npy)")
    with tempfile.TemporaryDirectory() as tmp:
        for mins in sorted({minutes / 3, minutes}):
            for kind in ("random", "stepped"):
                path = Path(tmp) / f"{kind}_{mins:g}.npy"
                t0 = time.perf_counter()
                plan = write_record(path, mins, fs, kind)
                gen = time.perf_counter() - t0
                arr = np.load(path, mmap_mode="r")
                size = arr.nbytes / 2**20
                if kind == "random":
                    e, dt, peak = timed(lambda: h1(arr[0], arr[1], [arr[2], arr[3]], nperseg=1 << 14))
                else:
                    e, dt, peak = timed(lambda: stepped_sine(arr[0], arr[1], [arr[2], arr[3]], plan=plan))
                print(f"  {kind:8s} {mins:4g} min ({arr.shape[1] / 1e6:.1f} M samples × 4 rows = {size:.0f} MiB on disk, "
                      f"written in {gen:.1f} s): {e.method} over {e.frequency_hz.size} lines in {dt:.2f} s, "
                      f"peak traced memory {peak / 2**20:.1f} MiB")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--fs", type=float, default=10_000.0)
    ap.add_argument("--skip-big", action="store_true")
    args = ap.parse_args(argv)
    nv = welch_coverage(args.draws)
    stepped_coverage(args.draws)
    naive_comparison(nv)
    if not args.skip_big:
        big_record(args.minutes, args.fs)


if __name__ == "__main__":
    main()
