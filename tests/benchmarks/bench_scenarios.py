"""Benchmark of the front door: wall time of every bundled scenario (full and quick), and the
throughput of ``ipmc study`` on each backend (serial, local processes, Dask LocalCluster), with
the identical-table check.  Run as a script: ``python3 tests/benchmarks/bench_scenarios.py``."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from scenarios.runner import run_scenario
from scenarios.spec import bundled_scenarios, load_scenario
from scenarios.study import load_study, parse_study, run_study


def scenarios_section():
    print("== scenarios (wall time [s], checks passed)")
    with tempfile.TemporaryDirectory() as tmp:
        for p in bundled_scenarios():
            row = [f"{p.stem:20s}"]
            for quick in (False, True):
                t0 = time.perf_counter()
                res = run_scenario(load_scenario(p, quick=quick), Path(tmp) / f"{p.stem}_{quick}", quiet=True)
                row.append(f"{'quick' if quick else 'full '} {time.perf_counter() - t0:6.1f} s "
                           f"{sum(c.passed for c in res.checks)}/{len(res.checks)}")
            print("  ".join(row))


def study_section():
    spec = load_study(Path(__file__).parents[2] / "scenarios" / "studies" / "actuator_mc.toml")
    big = parse_study({"study": {**{k: v for k, v in spec.items() if k not in ("frequencies_hz",)},
                                 "samples": 4000, "chunk_size": 250, "fmin_hz": 0.1, "fmax_hz": 10.0,
                                 "points": 40}})
    print(f"== study: {big['samples']} samples x {len(big['temperatures_c'])} T x {len(big['frequencies_hz'])} f")
    ref = None
    for label, kw in (("serial", {"backend": "serial"}), ("processes x2", {"workers": 2})):
        t0 = time.perf_counter()
        tab = run_study(big, **kw)
        dt = time.perf_counter() - t0
        ref = ref or tab
        print(f"{label:22s} {dt:6.2f} s  {tab.n_rows / dt / 1e6:5.2f} M rows/s  identical: {tab.equals(ref)}")
    from distributed import LocalCluster

    for procs in (False, True):
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=procs, dashboard_address=None) as cl:
            t0 = time.perf_counter()
            tab = run_study(big, scheduler=cl.scheduler_address)
            dt = time.perf_counter() - t0
        print(f"{'dask ' + ('processes' if procs else 'threads') + ' x2':22s} {dt:6.2f} s  "
              f"{tab.n_rows / dt / 1e6:5.2f} M rows/s  identical: {tab.equals(ref)}")


if __name__ == "__main__":
    scenarios_section()
    study_section()
