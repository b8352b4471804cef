"""Per-parameter-set overhead of the physics (issue 17): cost per point of many sets × few
frequencies against one set × many frequencies, and the cost of ``state_at`` per set.

    python tests/benchmarks/bench_sets.py            # about 10 s on 2 cores

Goal: 10k sets × 10 frequencies within 2× the per-point cost of 1 set × 100k frequencies.
The sets differ in d and E (as a Monte Carlo study's do) and share their temperature laws.
A model turns its sets into arrays once, when built (``ParameterTable``); the evaluation
ratio is the goal's, the "one-shot" ratio also counts building the 10k-set model.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # this checkout's packages

from _timing import best_of  # noqa: E402

from physmodel import ActuatorModel, get_parameter_set, state_at  # noqa: E402


def main() -> None:
    base = get_parameter_set("seed001_actuator")
    rng = np.random.default_rng(7)
    n_sets = 10_000
    sets = [base.replace(d=base.d * float(a), E=base.E * float(b))
            for a, b in zip(rng.lognormal(0, 0.3, n_sets), rng.lognormal(0, 0.1, n_sets), strict=True)]
    temps = [35.0]
    f_few = np.logspace(-1, 1, 10)
    f_many = np.logspace(-1, 1, 100_000)
    many_sets = ActuatorModel(sets)
    one_set = ActuatorModel(base)
    t_sets = best_of(lambda: many_sets.frequency_response(f_few, temps, quantities=("M",)), 3)
    t_freq = best_of(lambda: one_set.frequency_response(f_many, temps, quantities=("M",)), 3)
    t_state = best_of(lambda: state_at(sets, [20.0, 35.0, 50.0]), 3)
    t_build = best_of(lambda: ActuatorModel(sets), 3)
    per_sets = t_sets / (n_sets * f_few.size) * 1e9
    per_freq = t_freq / f_many.size * 1e9
    print(f"10k sets x 10 f      : {t_sets * 1e3:8.1f} ms  {per_sets:7.1f} ns/point")
    print(f"1 set x 100k f       : {t_freq * 1e3:8.1f} ms  {per_freq:7.1f} ns/point")
    print(f"ratio (goal <= 2)    : {per_sets / per_freq:8.2f}")
    print(f"building the 10k-set model: {t_build * 1e3:.1f} ms; one-shot ratio (build + evaluate): "
          f"{(t_sets + t_build) / (n_sets * f_few.size) * 1e9 / per_freq:.2f}")
    print(f"state_at, 10k sets x 3 T: {t_state * 1e3:.1f} ms ({t_state / n_sets * 1e6:.2f} us/set)")


if __name__ == "__main__":
    main()
