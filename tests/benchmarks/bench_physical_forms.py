"""What the diagnosis names for the effects issue 27 item 4 gave a physical form (run by hand).

    python3 tests/benchmarks/bench_physical_forms.py --first-seed 9500 --n-per-label 3 --workers 1
    python3 tests/benchmarks/bench_physical_forms.py --labels act:bending_modes sen:mount --n-per-label 2

Cases come from the independent generators (tests/discrepancy; they do not import the library's
effect code), run through ``diagnose`` as a user would (geometry, a generic start set, the laws;
nothing of the hidden effect):

``act:bending_modes``   the cantilever's modes 2..8 with one modal damping ratio of their own
                        (ζ_h 0.2 → 0.01), 41 lines 0.02-200 Hz (the second mode in band), 5
                        temperatures 19-55 °C; expected ``higher_modes``
``act:second_mode``     the generator's Rayleigh-damped modal sum in the same wide band (the old form)
``act:distributed_cpe`` an interface CPE in every slice of the electrode line (n 0.95-0.6, q_area
                        2000-2 F s^(n-1)/m²), the generator's 0.05-50 Hz band; expected ``distributed_cpe``
``act:series_cpe``      the CPE at the terminals (the old form), same band
``act:none``            null data, wide band (false positives with the new candidates)
``act:fixture_resonance`` the generator's out-of-library biquad resonance (expected ``unexplained``; does
                        ``clamp_mount``, a physical mount with a pole and a zero pair, take it?)
``sen:mount``           seed 000 sensor, the tip's mount on a joint damped by the water: a plain
                        second-order resonance (f_m 1500 → 60 Hz, ζ 0.05-0.3), 10-100 Hz; expected
                        ``mount_resonance``
``sen:joint``           the mount with the joint's own damping (the old form, ``fixture_joint``)
``sen:none``            null sensor data

Actuator: the user frees alpha0, d, kappa_e, xi, omega_n (bench_discrepancy's independent set-up);
sensor: a0, d, kappa_e with the chain candidates of scenarios.steps_chain plus any library
``mount_resonance`` (bench_chain_detection's set-up).  Detectable: the generator's own baseline
refit keeps λ ≥ 25.  An outcome counts as correct when the truth is named exactly, or the verdict is
``ambiguous`` listing the truth and every other name declared confusable with it (by the report or
by the library's ``CONFUSABLE``).  The same script runs on an older checkout (copy it and the
generators there) to measure "before": names the library lacks are simply never candidates.

Measured (issue 27 item 4, 2026-11-26, shared 2-core machine, load ≈ 7, before and after running at
the same time; "before" = main a0ebfbf with this script and the generators copied in, "after" = this
branch; seeds 9500-9523 held out, never looked at before these runs)::

    ... bench_physical_forms.py --first-seed 9500 --n-per-label 3 --workers 1

    label (detectable / 3)       before (a0ebfbf)                              after
    act:bending_modes   (3)      named second_mode 3 (the old form)            named higher_modes 3/3
    act:second_mode     (3)      named second_mode 3/3                         named second_mode 3/3
    act:distributed_cpe (2)      unexplained 1, at_bound series_cpe 1: 0/2     named distributed_cpe 2/2
    act:series_cpe      (2)      named series_cpe 2/2                          named series_cpe 2/2
    act:none (FP)                0/3                                           0/3
    sen:mount           (3)      at_bound tip_driven_beam 2, ambiguous         named mount_resonance 1, ambiguous
                                 fixture_joint+tip_driven_beam 1: 0/3          {fixture_joint, mount_resonance,
                                                                               tip_driven_beam} 2 (declared): 3/3
    sen:joint           (1)      ambiguous fixture_joint+tip_driven_beam 1     ambiguous with mount_resonance too 1
    sen:none (FP)                0/3                                           0/3
    s per diagnosis              mean 63.1, median 50.4, max 184.3             mean 69.7, median 57.0, max 203.0

Second held-out batch (seeds 9600-9608, same conditions)::

    ... bench_physical_forms.py --labels act:distributed_cpe sen:mount act:fixture_resonance \
        --first-seed 9600 --n-per-label 3 --workers 1

    label (detectable / 3)       before (a0ebfbf)                              after
    act:distributed_cpe (3)      unexplained 2, ambiguous without it 1: 0/3    named distributed_cpe 2, ambiguous
                                                                               with fractional_transport, series_cpe,
                                                                               viscous_fluid (declared) 1: 3/3
    sen:mount           (3)      at_bound tip_driven_beam 2, ambiguous         named mount_resonance 1, ambiguous
                                 fixture_joint+tip_driven_beam 1: 0/3          listing it (declared) 2: 3/3
    act:fixture_resonance        unexplained 3/3                               unexplained 3/3 (clamp_mount takes none)
    s per diagnosis              mean 71.4                                     mean 76.6

The ambiguous mount cases have their resonance above the band (f_m 308 and 486 Hz with 10-100 Hz
data): there every second-order element shows only its low-frequency lag and curvature, and the
report declares the three confusable from the data.  The generator's bending modes (one modal
damping ratio, 0.02-200 Hz) were already named ``second_mode`` before (its Rayleigh damping reaches
the same ζ2); after, the two forms are told apart both ways (LR margins 1e2-1.5e4).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "discrepancy")]

import independent_generator as ig  # noqa: E402
import independent_sensor as isn  # noqa: E402

from physmodel import IPMCParameters, get_parameter_set  # noqa: E402
from physmodel.effects import LIBRARY  # noqa: E402
from physmodel.estimation.discrepancy import diagnose  # noqa: E402

WIDE_HZ = np.logspace(math.log10(0.02), math.log10(200.0), 41)
FREE_ACT = ("alpha0", "d", "kappa_e", "xi", "omega_n")
WORKFLOW_FREE_GENERATOR = ("alpha", "d", "eps", "zeta", "f1")
DETECTABLE = 25.0
LABELS = ("act:bending_modes", "act:second_mode", "act:distributed_cpe", "act:series_cpe", "act:none",
          "act:fixture_resonance", "sen:mount", "sen:joint", "sen:none")
WIDE = ("bending_modes", "second_mode", "none")


def _declared(d):
    out = {frozenset(x[:2]) for x in d.confusable}
    try:
        from physmodel.effects import CONFUSABLE
        out |= set(CONFUSABLE)
    except ImportError:                    # an older library declares none with the effects
        pass
    return out


def run_case(item):
    label, seed = item
    kind, name = label.split(":")
    t0 = time.perf_counter()
    if kind == "act":
        kw = dict(frequencies_hz=WIDE_HZ) if name in WIDE else {}
        sweep, truth = ig.make_case(seed, name, workflow_free=WORKFLOW_FREE_GENERATOR, **kw)
        base = IPMCParameters.from_dict(dict(truth["library_start"]))
        t0 = time.perf_counter()
        d = diagnose(sweep, base, kind="actuator", free=FREE_ACT, alpha=0.05, seed=seed)
        lam = truth["lam_baseline"] or 0.0
    else:
        from scenarios.steps_chain import CANDIDATES, physics_free

        sweep, truth = isn.make_case(seed, name)
        p0 = get_parameter_set("seed000_sensor_dev", T_ref=isn.TEMPERATURE_C + 273.15)
        cands = list(CANDIDATES) + [c for c in ("mount_resonance",) if c in LIBRARY and c not in CANDIDATES]
        t0 = time.perf_counter()
        d = diagnose(sweep, p0, kind="sensor", free=physics_free(p0, ["a0", "d", "kappa_e"], math.copysign(1, p0.a0)),
                     candidates=cands, null_draws=1000, null_refits=2, baseline_starts=2, seed=1)
        lam = truth["lam_baseline"]
    dt = time.perf_counter() - t0
    top = sorted(d.candidates.values(), key=lambda c: -c.lr)[:3]
    return {"label": label, "seed": seed, "expected": truth["expected"], "lam": lam, "detectable": lam >= DETECTABLE,
            "verdict": d.verdict, "named": sorted(d.named), "declared": sorted(sorted(x) for x in _declared(d)),
            "top": [(c.name, round(float(c.lr), 2)) for c in top], "t": dt, "effects": truth["effects"]}


def correct(r):
    t = r["expected"]
    if not t:
        return False
    if r["verdict"] == "named":
        return r["named"] == t
    if r["verdict"] == "ambiguous":
        dec = {frozenset(x) for x in r["declared"]}
        return all(x in r["named"] for x in t) and all(any(frozenset((x, o)) in dec for x in t)
                                                       for o in r["named"] if o not in t)
    return False


def outcome(r):
    if r["verdict"] in ("named", "at_bound", "ambiguous"):
        return f"{r['verdict']} " + "+".join(r["named"])
    return r["verdict"]


def report(rows):
    by = defaultdict(list)
    for r in rows:
        by[r["label"]].append(r)
    print("\nlabel                   n  detectable  correct(det)  exact(det)  outcomes")
    for lab in LABELS:
        rr = by.get(lab)
        if not rr:
            continue
        det = [r for r in rr if r["detectable"]]
        ok = sum(correct(r) for r in det)
        ex = sum(r["verdict"] == "named" and r["named"] == r["expected"] for r in det)
        c = Counter(outcome(r) + ("" if r["detectable"] else " (not det.)") for r in rr)
        if lab.endswith(":fixture_resonance"):
            un = sum(r["verdict"] == "unexplained" for r in rr)
            print(f"{lab:22s} {len(rr):2d}  unexplained {un}/{len(rr)}                   " + "; ".join(
                f"{k} ×{v}" for k, v in c.items()))
            continue
        if lab.endswith(":none"):
            fp = sum(r["verdict"] in ("named", "ambiguous", "at_bound") for r in rr)
            print(f"{lab:22s} {len(rr):2d}  FP {fp}/{len(rr)}                           " + "; ".join(
                f"{k} ×{v}" for k, v in c.items()))
            continue
        print(f"{lab:22s} {len(rr):2d}  {len(det):2d}          {ok}/{len(det)}           {ex}/{len(det)}        "
              + "; ".join(f"{k} ×{v}" for k, v in c.items()))
    ts = np.array([r["t"] for r in rows])
    print(f"\ntime per diagnosis: mean {ts.mean():.1f} s, median {np.median(ts):.1f} s, max {ts.max():.1f} s (n = {ts.size})")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--labels", nargs="*", default=[lab for lab in LABELS if lab != "act:fixture_resonance"],
                    choices=LABELS)
    ap.add_argument("--n-per-label", type=int, default=3)
    ap.add_argument("--first-seed", type=int, default=9500)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--json", help="write the rows here (one JSON object per line)")
    a = ap.parse_args(argv)
    plan = [(lab, a.first_seed + i * a.n_per_label + k) for i, lab in enumerate(a.labels) for k in range(a.n_per_label)]
    rows = []
    if a.workers > 1:
        from multiprocessing import get_context

        with get_context("spawn").Pool(a.workers) as pool:
            rows = list(pool.imap(run_case, plan))
    else:
        for item in plan:
            r = run_case(item)
            rows.append(r)
            print(f"{r['label']:22s} seed {r['seed']} λ={r['lam']:10.1f} -> {outcome(r):50s} top {r['top']} "
                  f"{r['t']:.1f} s", flush=True)
    if a.json:
        with open(a.json, "w") as fh:
            for r in rows:
                fh.write(json.dumps(r, default=float) + "\n")
    report(rows)


if __name__ == "__main__":
    main()
