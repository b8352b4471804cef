"""Timing helpers shared by the benchmark scripts (not collected by pytest).

Wall times on a shared machine are noisy: time the candidates interleaved (A B A B ...), so a
drift of the machine's speed hits all of them alike, and reduce each one's repeats to its best
(``min``, the least disturbed run) or its median.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable

import numpy as np


def interleaved(fns: dict[str, Callable[[], object]], reps: int, reduce=np.median,
                clock: Callable[[], float] = time.perf_counter) -> dict[str, float]:
    """Time [s] of each callable over ``reps`` interleaved rounds, reduced by ``reduce``: wall time,
    or with ``clock=time.thread_time`` this thread's CPU time (on a shared machine the wall time
    also counts the time other processes run)."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(reps):
        for k, f in fns.items():
            gc.collect()
            t0 = clock()
            f()
            times[k].append(clock() - t0)
    return {k: float(reduce(v)) for k, v in times.items()}


def best_of(fn: Callable[[], object], repeat: int = 5) -> float:
    """Best wall time [s] of ``repeat`` calls of ``fn``."""
    return interleaved({"fn": fn}, repeat, reduce=np.min)["fn"]
