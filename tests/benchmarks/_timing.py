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


def interleaved(fns: dict[str, Callable[[], object]], reps: int, reduce=np.median) -> dict[str, float]:
    """Wall time [s] of each callable over ``reps`` interleaved rounds, reduced by ``reduce``."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(reps):
        for k, f in fns.items():
            gc.collect()
            t0 = time.perf_counter()
            f()
            times[k].append(time.perf_counter() - t0)
    return {k: float(reduce(v)) for k, v in times.items()}


def best_of(fn: Callable[[], object], repeat: int = 5) -> float:
    """Best wall time [s] of ``repeat`` calls of ``fn``."""
    return interleaved({"fn": fn}, repeat, reduce=np.min)["fn"]
