"""Benchmark: throughput of the full actuator M(jω) against a single complex np.tanh.

Run:  python tests/benchmarks/bench_physmodel.py [--points N] [--big 1e7]

Reports points/s of M (seed002_table3, 1e-2..1e4 Hz × 0..90 °C grid), points/s of one np.tanh over
a complex array of the same size, their ratio (the issue's goal: M costs at most 3 tanh per point),
and the peak extra memory (tracemalloc) of evaluating 1e7 points into a preallocated output.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc

import numpy as np
from _timing import best_of

from physmodel import ActuatorModel, get_parameter_set


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--points", type=int, default=1_000_000, help="grid points for the timing (default 1e6)")
    ap.add_argument("--big", type=float, default=1e7, help="points for the memory check (default 1e7)")
    ap.add_argument("--repeat", type=int, default=15, help="interleaved repetitions; best time of each kept")
    args = ap.parse_args(argv)

    n_T = 10
    n_f = args.points // n_T
    f = np.logspace(-2, 4, n_f)
    T = np.linspace(0, 90, n_T)
    model = ActuatorModel(get_parameter_set("seed002_table3"))
    st = model.state(T)
    from physmodel.actuator import actuator_kernel
    from physmodel.model import evaluate_grid

    s = 2j * np.pi * f
    z = (np.broadcast_to(s, (n_T, n_f)) * 1e-3 + 1.0).ravel().copy()
    # interleave the two timings so that load from other processes hits both alike
    t_model = t_tanh = np.inf
    for _ in range(args.repeat):
        t_model = min(t_model, best_of(lambda: evaluate_grid(st, s, actuator_kernel, ("M",), model.chunk_size), 1))
        t_tanh = min(t_tanh, best_of(lambda: np.tanh(z), 1))
    n = n_T * n_f
    print(f"points                      : {n:,}")
    print(f"M(jw) throughput            : {n / t_model:,.0f} points/s  ({t_model * 1e9 / n:.1f} ns/point)")
    print(f"np.tanh (complex) throughput: {n / t_tanh:,.0f} points/s  ({t_tanh * 1e9 / n:.1f} ns/point)")
    print(f"cost of M in complex tanh   : {t_model / t_tanh:.2f}  (goal <= 3)")

    nbig = int(args.big)
    n_f_big = nbig // n_T
    fb = np.logspace(-2, 4, n_f_big)
    out = {"M": np.empty((1, n_T, n_f_big), dtype=complex)}
    tracemalloc.start()
    t0 = time.perf_counter()
    model.frequency_response(fb, T, quantities=("M",), out=out)
    dt = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    print(f"{n_T * n_f_big:,} points into a preallocated output: {dt:.2f} s, "
          f"peak extra memory {peak / 2**20:.1f} MiB (output itself {out['M'].nbytes / 2**20:.0f} MiB)")


if __name__ == "__main__":
    main()
