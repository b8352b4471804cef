"""Benchmark and figures for the ``inversion`` package.

Run:  python tests/benchmarks/bench_inversion.py [--quick] [--skip-10h]

Prints
  1. batch throughput of ``invert`` on the 4th-order 35 degC sensor model, as a ratio to
     ``scipy.signal.lfilter`` running a 4th-order filter over the same samples in the same
     run (interleaved repetitions, best of N; goal >= 0.3);
  2. streaming cost per sample for several chunk sizes;
  3. a 10-hour, 1 kHz record (3.6e7 samples) inverted from and to memory-mapped files:
     wall time, peak Python heap (tracemalloc) and peak RSS;
  4. the seed-000 preview figures (20 Hz, 35 degC): error with T_p*, 0.5 T_p*, infinite;
  5. free vibration after release: pre-actuation error before the release instant;
  6. drifting bath: scheduled vs fixed-temperature inverse.
Not collected by pytest (the file name does not start with ``test_``).
"""

from __future__ import annotations

import argparse
import gc
import os
import resource
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
import scipy.signal as ss

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from inversion import (  # noqa: E402
    StreamingInverter,
    invert,
    invert_scheduled,
    invert_to,
    split_inverse,
)
from inversion.examples import (  # noqa: E402
    released_cantilever,
    seed000_sensor_35c,
    toy_scheduled_sensor,
)

G35 = seed000_sensor_35c("coefficients")


def _best(fns: dict, reps: int) -> dict:
    times = {k: [] for k in fns}
    for _ in range(reps):
        for k, f in fns.items():
            gc.collect()
            t0 = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t0)
    return {k: min(v) for k, v in times.items()}


def bench_batch(n: int, reps: int) -> None:
    print(f"\n1. batch throughput, 4th-order model, n = {n:,} samples, best of {reps}")
    dt = 1e-3
    u = np.sin(2 * np.pi * 20 * dt * np.arange(n)) + 0.1 * np.random.default_rng(0).standard_normal(n)
    b, a = ss.butter(4, 0.1)
    sp = split_inverse(G35)
    fns = {
        "lfilter (4th order)": lambda: ss.lfilter(b, a, u),
        "invert preview=inf": lambda: invert(sp, dt, u, preview="inf"),
        "invert preview=auto": lambda: invert(sp, dt, u, preview="auto"),
    }
    best = _best(fns, reps)
    base = best["lfilter (4th order)"]
    for k, v in best.items():
        print(f"   {k:22s} {v / n * 1e9:7.2f} ns/sample  {n / v / 1e6:7.1f} Msample/s  "
              f"ratio to lfilter {base / v:5.2f}")


def bench_streaming(n: int) -> None:
    print(f"\n2. streaming cost per sample (35 degC model, dt = 1 ms, preview auto = 0.113 s)")
    dt = 1e-3
    u = np.sin(2 * np.pi * 20 * dt * np.arange(n))
    for chunk in (1, 16, 256, 4096):
        m = n if chunk >= 256 else min(n, 20_000 * chunk)
        inv = StreamingInverter(G35, dt, "auto")
        t0 = time.perf_counter()
        for i in range(0, m, chunk):
            inv.push(u[i:i + chunk])
        el = time.perf_counter() - t0
        # history independence: cost of the second half vs the first half
        inv2 = StreamingInverter(G35, dt, "auto")
        half = m // 2
        t1 = time.perf_counter()
        for i in range(0, half, chunk):
            inv2.push(u[i:i + chunk])
        t2 = time.perf_counter()
        for i in range(half, m, chunk):
            inv2.push(u[i:i + chunk])
        t3 = time.perf_counter()
        print(f"   chunk {chunk:5d}: {el / m * 1e9:9.0f} ns/sample over {m:,} samples; "
              f"first half {(t2 - t1) / half * 1e9:8.0f}, second half {(t3 - t2) / (m - half) * 1e9:8.0f} ns/sample")
    for N_s in (0.01, 1.0):
        inv = StreamingInverter(G35, dt, N_s)
        t0 = time.perf_counter()
        for i in range(0, n, 256):
            inv.push(u[i:i + 256])
        el = time.perf_counter() - t0
        print(f"   preview {N_s:5.2f} s ({inv.preview_samples} samples), chunk 256: {el / n * 1e9:7.0f} ns/sample")


def bench_10h(hours: float, chunk: int) -> None:
    dt = 1e-3
    n = int(round(hours * 3600 / dt))
    print(f"\n3. {hours:g}-hour record at 1 kHz: {n:,} samples ({n * 8 / 2**20:,.0f} MiB per array), "
          f"memory-mapped in/out, chunk {chunk:,}")
    with tempfile.TemporaryDirectory(dir=os.environ.get("TMPDIR", "/tmp")) as d:
        src = np.lib.format.open_memmap(os.path.join(d, "u.npy"), mode="w+", dtype=float, shape=(n,))
        for c0 in range(0, n, chunk):
            k = np.arange(c0, min(n, c0 + chunk))
            src[c0:c0 + k.size] = np.sin(2 * np.pi * 20 * dt * k) * (1 + 0.5 * np.sin(2 * np.pi * k * dt / 600))
        src.flush()
        dst = np.lib.format.open_memmap(os.path.join(d, "y.npy"), mode="w+", dtype=float, shape=(n,))
        rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        for preview in ("inf", "auto"):
            tracemalloc.start()
            t0 = time.perf_counter()
            invert_to(G35, dt, src, dst, preview=preview, chunk_size=chunk)
            el = time.perf_counter() - t0
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            dst.flush()
            rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
            # spot check against an in-memory inversion of the last 20 s with enough lead-in
            print(f"   preview={preview:4s}: {el:6.1f} s ({n / el / 1e6:5.1f} Msample/s), "
                  f"peak heap {peak / 2**20:6.1f} MiB, peak RSS so far {rss1 / 1024:7.1f} MiB "
                  f"(start {rss0 / 1024:.1f} MiB; RSS includes touched pages of the mapped files)")
        del src, dst


def figures_seed000() -> None:
    print("\n4. seed 000 preview claims (35 degC, 20 Hz, model-exact virtual experiment, d0 = 1 mm)")
    for form in ("zeros", "coefficients"):
        sp = split_inverse(seed000_sensor_35c(form))
        print(f"   {form:12s} model: r0 = {sp.r0:.4g} 1/s, T_p* = 4/r0 = {sp.auto_preview_s:.4g} s")
    G = seed000_sensor_35c("zeros")
    num, den = np.asarray(G.num[0][0]), np.asarray(G.den[0][0])
    dt, w = 1e-4, 2 * np.pi * 20
    t = np.arange(0.0, 2.0, dt)
    g = np.polyval(num, 1j * w) / np.polyval(den, 1j * w)
    i = abs(g) * np.sin(w * t + np.angle(g))
    d = np.sin(w * t)
    m = (t > 0.6) & (t < 1.3)
    Ts = split_inverse(G).auto_preview_s
    errs = {}
    for name, pv in (("infinite", "inf"), ("T_p*", Ts), ("0.5 T_p*", 0.5 * Ts)):
        r = invert(G, t, i, preview=pv)
        errs[name] = np.max(np.abs(r.output[m] - d[m]))
        print(f"   preview {name:9s} ({r.preview_s:.4g} s): max error {errs[name]:.4g} mm per mm of stimulus")
    print(f"   ratio 0.5 T_p* / T_p*: {errs['0.5 T_p*'] / errs['T_p*']:.2f}  (exp(2) = {np.exp(2):.2f})")
    floor, amp = 0.2, 3.0
    tot = {k: np.hypot(floor, amp * v) for k, v in errs.items()}
    print(f"   with the paper's ~0.2 mm floor (added in quadrature) and a 3 mm stimulus: "
          f"inf {tot['infinite']:.3f}, T_p* {tot['T_p*']:.3f}, 0.5 T_p* {tot['0.5 T_p*']:.3f} mm "
          f"-> ratio {tot['0.5 T_p*'] / tot['T_p*']:.2f}")


def _released_current(G, t, fine=10, **kw):
    num, den = np.asarray(G.num[0][0], float), np.asarray(G.den[0][0], float)
    A, B, C, D = ss.tf2ss(num, den)
    x0 = -np.linalg.solve(A, B).ravel() * kw["w0"]
    dtf = (t[1] - t[0]) / fine
    tf = np.arange((t.size - 1) * fine + 1) * dtf
    _, y, _ = ss.lsim((A, B, C, D), released_cantilever(tf, **kw), tf, X0=x0)
    return y[::fine]


def figures_free_vibration() -> None:
    print("\n5. free vibration after release (35 degC sensor, w0 = 1 mm, 25 Hz, zeta = 0.1, "
          "release at 0.6 s, dt = 1 ms)")
    dt, tr = 1e-3, 0.6
    t = np.arange(0.0, 2.0, dt)
    kw = dict(w0=1.0, t_release=tr, f_n=25.0, zeta=0.1)
    disp = released_cantilever(t, **kw)
    G = seed000_sensor_35c("zeros")
    pre = (t >= tr - 0.3) & (t < tr)
    post = (t >= tr) & (t < 1.5)
    for label, truth in (("matched model", G), ("sensor at 36 degC, model 35 degC", toy_scheduled_sensor(36.0))):
        i = _released_current(truth, t, **kw)
        for pv in ("inf", "auto"):
            r = invert(G, t, i, preview=pv)
            e = r.output - disp
            hold = e[(t > 0.2) & (t < tr - 0.3)].mean()
            print(f"   {label:33s} preview {pv:4s}: pre-release max |error| {np.max(np.abs(e[pre])):.3g} mm "
                  f"(hold-phase offset {hold:+.3g}, transient at t_r-1ms {e[int(round((tr - 1e-3) / dt))] - hold:+.3g}); "
                  f"post-release max {np.max(np.abs(e[post])):.3g} mm")


def figures_drift() -> None:
    print("\n6. drifting bath 30 -> 40 degC over 2.5 s, 20 Hz 1 mm stimulus, toy scheduled sensor")
    from scipy.integrate import solve_ivp
    import scipy.linalg as sla
    from inversion.examples import SEED000_DEN_35C, SEED000_NUM_35C

    dt, dur = 1e-3, 2.5
    t = np.arange(0.0, dur, dt)
    Tf = lambda tt: 30.0 + 10.0 * tt / dur
    dfun = lambda tt: np.where(tt < 0.3, np.sin(np.pi * tt / 0.6) ** 2, 1.0) * np.sin(2 * np.pi * 20 * tt)
    A, B, C, D = ss.tf2ss(SEED000_NUM_35C, SEED000_DEN_35C)
    A, (sc, _) = sla.matrix_balance(A, permute=False, separate=True)
    B, C, D = B.ravel() / sc, C.ravel() * sc, float(D[0, 0])
    kap = lambda TT: 1 - 0.01 * (TT - 35)
    gain = lambda TT: 1 - 0.004 * (TT - 35)
    sol = solve_ivp(lambda tt, x: kap(Tf(tt)) * (A @ x + B * dfun(tt)), (0, t[-1]), np.zeros(4),
                    t_eval=t, method="DOP853", rtol=1e-10, atol=1e-12, max_step=2e-4)
    i = gain(Tf(t)) * (C @ sol.y + D * dfun(t))
    d = dfun(t)
    m = (t > 0.5) & (t < dur - 0.3)
    for pv in ("inf", "auto"):
        s = invert_scheduled(toy_scheduled_sensor, t, i, Tf(t), preview=pv)
        f30 = invert(toy_scheduled_sensor(30.0), t, i, preview=s.preview_s)
        f35 = invert(toy_scheduled_sensor(35.0), t, i, preview=s.preview_s)
        es, e30, e35 = (np.max(np.abs(r.output[m] - d[m])) for r in (s, f30, f35))
        print(f"   preview {pv:4s}: scheduled {es:.3g} mm, fixed 30 degC {e30:.3g} mm ({e30 / es:.0f}x), "
              f"fixed 35 degC {e35:.3g} mm ({e35 / es:.0f}x); grid {s.grid_c.size} nodes")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes (and a 1-hour record)")
    ap.add_argument("--skip-10h", action="store_true", help="skip the long-record test")
    args = ap.parse_args()
    n = 1 << (20 if args.quick else 22)
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, scipy {__import__('scipy').__version__}, "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}")
    bench_batch(n, 3 if args.quick else 7)
    bench_streaming(1 << (17 if args.quick else 19))
    if not args.skip_10h:
        bench_10h(1.0 if args.quick else 10.0, 1 << 20)
    figures_seed000()
    figures_free_vibration()
    figures_drift()


if __name__ == "__main__":
    main()
