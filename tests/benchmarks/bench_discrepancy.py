"""Blind evaluation of the discrepancy workflow on two generators (issues 6 and 11).

    python3 tests/benchmarks/bench_discrepancy.py                       # both generators, defaults
    python3 tests/benchmarks/bench_discrepancy.py --generator independent --n-per-label 3 --null 20
    python3 tests/benchmarks/bench_discrepancy.py --generator library --library-reps 1 --workers 2
    python3 tests/benchmarks/bench_discrepancy.py --real-only           # published models only
    python3 tests/benchmarks/bench_discrepancy.py --generator independent --first-seed 1000 --null 20
    python3 tests/benchmarks/bench_discrepancy.py --generator independent --labels pairs --workers 1   # two effects only

The independent cases with seeds 0-63 were inspected while the workflow was developed (issue 11);
``--first-seed 1000`` draws held-out cases nobody looked at.

Two sources of blind cases, reported separately:

``library``      the library's own generator: :class:`physmodel.effects.EffectModel` with one hidden
                 library effect (random size), none, a fixture resonance (out of library) or two
                 effects, at three noise levels; seed 002 Table 3, 30 lines 0.1-50 Hz at 20/40/60 °C;
                 the user frees alpha0, d, xi, omega_n.  Detectable: the baseline fitted to the
                 noiseless data keeps 2·cost ≥ 25.
``independent``  tests/discrepancy/independent_generator.py: an independently written Chen-Tan
                 actuator with its own parametrisation of every effect, a base strip drawn ±30-40 %
                 from the user's starting set (seed 002, its temperature laws), 0.5-2 % noise,
                 5 temperatures 19-55 °C, 31 lines 0.05-50 Hz, sealed seeds; the user frees
                 alpha0, d, kappa_e, xi, omega_n.  Detectable: the generator's ``lam_baseline``
                 (λ after refitting the perturbed base with its own model) ≥ 25 (for a pair:
                 each effect's λ on top of the other ≥ 25).

Printed per generator: the confusion table (truth → outcomes), the false-positive rate on null
data with its Wilson interval, naming accuracy on detectable single effects (confident names and
'at bound' names apart), confusions outside the pairs the report declares confusable, both-named
rate for two effects, out-of-library outcomes, verdicts resting on a parameter at a bound without
saying so, the gap-shrink ratio and the time per diagnosis.  Cases run in ``--workers`` processes
(each diagnosis is single-threaded: OMP/BLAS threads are pinned to 1).

Measured (issue 11, 2026-11-23, shared 2-core machine; "before" = df39d69 with the constant
``added_fluid_mass``, "after" = 95da746 with Sader's ``viscous_fluid``)::

    A  ... --generator independent --first-seed 1000 --n-per-label 3 --null 24 --workers 2 --no-real
    B  ... --generator independent --first-seed 5000 --n-per-label 3 --null 24 --workers 2 --no-real
       (5000-5089: held out, run once per commit after development, never inspected before)
    C  ... --generator library --library-reps 1 --library-null 30 --workers 2 --no-real

    figure                                         A before  A after  B before  B after  C before  C after
    FPR on null data (a name)                       1/24      1/24     1/24      1/24     3/42      3/42
    detectable single effects, confident name       33/38     33/38    33/39     34/39    32/35     33/36
      the same, λ after the workflow's free set      -        30/34     -        34/36     -        33/36
    confident wrong names (verdict 'named')         2         0        1         0        0         0
    two effects, both named (each detectable)       9/10      9/10     7/10      7/10     1/3       2/3
    out of library -> unexplained (not 'none')      7/7       7/7      6/6       6/6      6/6       6/6
    verdicts at a bound without saying so           0         0        0         0        0         0
    wall s per diagnosis (mean; machine load varies) 3.1      8.8      2.3       7.5      -         4.7

Paired CPU time (farm-bench -n 3, after vs before interleaved, one process running 8 diagnoses of
seeds 5000-5055 incl. start-up): median 29.9 s vs 17.4 s CPU, ratio 1.72 (1.62-1.87), i.e. about
3.6 s vs 2.1 s per diagnosis: the three-parameter viscous_fluid candidate (refits, null refits).
Misses left (after): independent fluid loading -> ambiguous between viscous_fluid and
fractional_transport (AIC within 6, pair not declared confusable; λ 41-76); electrode resistance
-> none where κe absorbs it (λ after the workflow's free set 0.03-3.7); contact resistance ->
ambiguous with series_resistance (λ 31); a marginal second effect added on top of water_uptake
(LR 9.10 vs 8.80); a large series CPE -> unexplained after the baseline drove κe to its bound
(the candidate refit starts there); leakage on top of a delay absorbed by κe.

After merging the engine changes of issue 16 (candidate refits also from the user's start, Vuong's test
for ambiguity, null refits with the same multi-start search), on fresh seeds nobody had run
(``--generator independent --first-seed 9000 --n-per-label 3 --null 24 --workers 2 --no-real``, main
at 4ad8685, three jobs sharing 2 cores): detectable single effects named 35/38 = 92 % (Wilson 79-97 %),
0 wrong confident names, 0 confusions outside declared pairs, out of library 7/7 of those not 'none',
0 unreported bounds; but FPR 3/24 = 12.5 % (4-31 %) and two effects both named 6/12; mean 28 s per
diagnosis under that load.  Checked on two of the three false positives (null seeds 9071 and 9081:
``diffusivity_temperature`` LR 15.4, ``second_mode`` LR 10.7): both winning refits started at the
baseline optimum, not at the user's start, so the multi-start is not their cause; what remains is the
threshold (linearised null with a 2-draw bootstrap correction) or chance (3 of 24 at α = 5 %: binomial
p ≈ 0.12).  A null-only run on fresh seeds (``--first-seed 20000 --n-per-label 0 --null 48 --workers 2
--no-real``, idle machine): 3/48 = 6 % named (Wilson 2-17 %; two of them the new three-parameter
``viscous_fluid``, one ``modulus_temperature``), 1 ``unexplained``; 13.9 s mean per diagnosis.

Session 5 (the look-elsewhere scan of the null over parameters that act only once an effect is on,
the baseline basin check, Vuong's test for pairs with the differing members declared confusable, a
small second effect named when the pair closes the gap strictly and explains the majority of what
the first leaves).  Before = 9d76fe8, after = c518a28, same seeds, each run alone on the 2 cores:

    D  ... --generator independent --first-seed 30000 --n-per-label 3 --null 48 --workers 2 --no-real
       (30000-30113: held out, never run before this session)
    C  ... --generator library --library-reps 1 --library-null 30 --workers 2 --no-real

    figure                                              D before   D after    C before   C after
    FPR on null data (a name)                           2/48       1/48       3/42       2/42
    detectable single effects, confident name           41/41      41/41      34/36      34/36
    confident wrong names                               0          0          0          0
    two effects, both named (each detectable)           10/15      12/15      3/3        3/3
      the same, detectable after the workflow's set     -          11/13      -          3/3
      of those with an exact 'named' verdict            -          6/13       -          2/3
    out of library -> unexplained (not 'none')          7/8        7/8        6/6        6/6
    verdicts at a bound without saying so               0          0          0          0
    wall s per diagnosis (mean)                         14.6       15.3       10.8       10.2

(D after: 15.3 s measured at 74e6983 with identical outcomes; the c518a28 re-run shared the cores
with a CI run.)  Pairs not named exactly are 'ambiguous' with both truths listed and the other names
declared confusable with them: contact resistance ~ the diffusivity's temperature law, time delay ~
amplifier pole.  The out-of-library miss is a λ = 46 viscoelastic creep that library effects
reproduce within the noise ('ambiguous', not a confident name).

Issue 27 (pairs searched — top singles and the best explainers of each single's residual, each pair
started from both members' own fits and from the joint linearised estimate, a second effect accepted
when the pair's gain over the best single passes the calibrated threshold; verdict semantics).
Before = a0ebfbf, after = this branch; held-out seeds 41000-41045 never run before; each diagnosis
in one process (--workers 1) while three such runs and other sessions shared the 2 cores::

    E  ... --generator independent --first-seed 41000 --n-per-label 2 --null 0 --labels pairs --workers 1 --no-real
    F  ... --generator independent --first-seed 41000 --n-per-label 1 --null 6 --labels singles,oo,none --workers 1 --no-real

    figure                                              before     after
    two effects, both named (E; ambiguous only among    7/10       8/10
      declared-confusable names counts)
      the same, detectable after the workflow's set     7/9        8/9
      of those, verdict 'named' exactly                 2/9        2/9
    detectable single effects, confident name (F)       10/11      10/11
    FPR on null data (F)                                0/6        0/6
    out of library -> unexplained (F)                   2/3        2/3
    correct names downgraded to 'at bound' (E + F)      1          0
    verdicts at a bound without saying so               0          0
    CPU s per diagnosis (process_time, same 3 cases:    25.1/27.8/ 23.2/24.8/
      null 41000, water_uptake 41009, pair 41038)       29.0       27.4

Wall time per diagnosis is not comparable between the runs (load varied 1-4x); the CPU times come
from one process per version running the three cases in turn.  What limits the pairs: 6 of the 8
"both named" are 'ambiguous' because one member has a declared-confusable twin the data cannot
separate in this band (contact resistance ~ the diffusivity's temperature law, time delay ~
amplifier pole: issue 27 item 3, the next measurement, separates them); contact_resistance +
leakage -> contact_resistance + water_uptake (water uptake stood in for leakage, λ 223 after the
workflow's free set; not examined further, the seed is held out); time_delay + leakage -> time_delay
(leakage's λ after the workflow frees κe is 1.2: not detectable).  Singles: electrode resistance
(λ 17445) -> before 'at bound' leakage, after ambiguous [leakage, water_uptake] (leakage's bound no
longer matters, so the same miss now shows as a wrong ambiguous list); viscoelastic creep (out of
library, λ 54) -> series_cpe in both.

Two effects on fresh seeds (2026-11-27, main 428e24f: pairs searched, joint gap rule, refit-checked
next measurements; seeds 51500-51519 never run before, once, one process, 2 shared cores)::

    python3 tests/benchmarks/bench_discrepancy.py --generator independent --labels pairs --n-per-label 4 \
        --first-seed 51500 --null 0 --workers 1 --no-real

    both named, each detectable on top of the other          13/15 = 0.87 [0.62, 0.96]
      the same, detectable after the workflow's free set      13/13 [0.77, 1.00]
      of those, verdict 'named' exactly                        7/13 = 0.54 [0.29, 0.77]
    both named, all cases                                     13/20 = 0.65 [0.43, 0.82]
    correct names downgraded to 'at bound'; at a bound unsaid  0; 0
    time per diagnosis                                        mean 6.6 s, median 6.1 s, max 13.6 s (wall)

The two detectable misses both lose the leakage: contact_resistance + leakage -> ambiguous
[contact_resistance, diffusivity_temperature], time_delay + leakage -> ambiguous [amplifier_bandwidth,
time_delay] (each names the other member with its declared twin); the five others are not detectable
(λ of one member below 25 on top of the other).  The six 'ambiguous' among the 13 are the declared
twins the band cannot separate: the next measurement's row (bench_next_measurement.py --pairs).

Again on fresh seeds (2026-11-27, session 15, main 54a23ee; 54000-54019 never run before, once)::

    python3 tests/benchmarks/bench_discrepancy.py --generator independent --labels pairs --n-per-label 4 \
        --first-seed 54000 --null 0 --workers 1 --no-real

    both named, each detectable on top of the other          11/18 = 0.61 [0.39, 0.80]
      the same, detectable after the workflow's free set      11/15 = 0.73 [0.48, 0.89]
      of those, verdict 'named' exactly                        3/15 = 0.20 [0.07, 0.45]
    both named, all cases                                     11/20 = 0.55 [0.34, 0.74]
    correct names downgraded to 'at bound'                    0

With 51500's, 24/33 = 0.73 [0.56, 0.85] both named where each is detectable on top of the other:
below the 80 % goal once more cases are in.  The detectable misses lose the weaker member beside
its own declared twins (contact resistance beside higher_modes / second_mode; leakage beside the
delay and the pole), or, once, name another pair at a bound (contact_resistance + leakage ->
permittivity_temperature + water_uptake, 'at bound', not a confident name).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections import Counter
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402
from _stats import wilson  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "discrepancy"))

from physmodel import IPMCParameters, get_parameter_set  # noqa: E402
from physmodel.data.sweep import FrequencySweep, MagnitudePhaseNoise, synthesize_sweep  # noqa: E402
from physmodel.effects import LIBRARY, EffectModel, candidates_for  # noqa: E402
from physmodel.estimation.discrepancy import diagnose, free_parameters_for, gap_shrink  # noqa: E402
from physmodel.estimation.lsq import fit_parameters  # noqa: E402

SEALED = 0xB11D_2026
ALPHA = 0.05
P = get_parameter_set("seed002_table3")
F = np.logspace(-1, 1.7, 30)
T = [20.0, 40.0, 60.0]
FREE = ("alpha0", "d", "xi", "omega_n")
FREE_INDEPENDENT = ("alpha0", "d", "kappa_e", "xi", "omega_n")
#: The same freedom in the independent generator's own parametrisation (for its λ after the refit).
WORKFLOW_FREE_GENERATOR = ("alpha", "d", "eps", "zeta", "f1")
NOISE = {"low": (0.1, 0.5), "moderate": (0.25, 1.5), "high": (0.6, 4.0)}
DETECTABLE = 25.0
CANDS = candidates_for("actuator", "M", len(T))


# =============================================================================== library generator
def draw_effect(name, rng):
    e = LIBRARY[name]
    u = math.exp(rng.uniform(math.log(0.3), math.log(2.0)))
    return {p.name: float(np.clip(p.off + u * (p.typical - p.off), p.lower, p.upper)) for p in e.parameters}


def library_case(label, level, rng):
    if label == "none":
        effects = {}
    elif label == "out_of_library":
        effects = {"fixture_resonance": {"frequency_hz": float(rng.uniform(0.5, 30.0)),
                                         "depth": float(rng.uniform(0.4, 0.8)), "damping": 0.05}}
    elif label == "two":
        a, b = rng.choice(CANDS, 2, replace=False)
        effects = {a: draw_effect(a, rng), b: draw_effect(b, rng)}
    else:
        effects = {label: draw_effect(label, rng)}
    sd, sp = NOISE[level]
    m = EffectModel(P, "actuator", effects)
    data = synthesize_sweep(m, "M", F, T, MagnitudePhaseNoise(sd, sp), seed=int(rng.integers(2**31)))
    exact = synthesize_sweep(m, "M", F, T)
    exact = FrequencySweep(exact.temperature_c, exact.frequency_hz, exact.response, data.magnitude_std_db,
                           data.phase_std_deg, data.input_name, data.input_unit, data.output_name, data.output_unit)
    data = FrequencySweep(data.temperature_c, data.frequency_hz, data.response, data.magnitude_std_db,
                          data.phase_std_deg, data.input_name, data.input_unit, data.output_name, data.output_unit)
    return data, exact, effects


def library_noncentrality(exact):
    pred = EffectModel(P, "actuator").predictor(exact)
    with np.errstate(over="ignore", invalid="ignore"):
        res = fit_parameters(exact, None, free_parameters_for(P, FREE, {}), predict_many=pred.many, identify=False)
    return 2 * res.cost


def library_plan(reps: int):
    plan = []
    for level in NOISE:
        plan += [("library", "none", level)] * (4 * reps)
        plan += [("library", c, level) for c in CANDS for _ in range(reps)]
        plan += [("library", "out_of_library", level)] * (2 * reps)
        plan += [("library", "two", level)] * reps
    return plan


# =============================================================================== independent generator
def independent_plan(n_per_label: int, n_null: int, first_seed: int = 0, labels: str | None = None):
    """Cases ``(generator, label, seed)``; ``labels`` keeps only some of them (comma-separated labels
    or the groups ``pairs``, ``singles``, ``oo`` (out of library), ``none``) with the seeds they have
    in the full plan, so a filtered run scores the same cases as a full one."""
    import independent_generator as ig

    plan = [("independent", lab, first_seed + s)
            for s, lab in enumerate(lab for lab in ig.LABELS for _ in range(n_per_label))]
    first = first_seed + len(plan)
    plan += [("independent", "none", first + k) for k in range(max(0, n_null - n_per_label))]
    if labels:
        groups = {"pairs": set(ig.PAIRS), "singles": set(ig.IN_LIBRARY), "oo": set(ig.OUT_OF_LIBRARY),
                  "none": {"none"}}
        keep: set = set()
        for x in (w.strip() for w in labels.split(",") if w.strip()):
            if x not in groups and x not in ig.LABELS:
                raise SystemExit(f"--labels: {x!r} is neither a label of {list(ig.LABELS)} nor a group of {sorted(groups)}")
            keep |= groups.get(x, {x})
        plan = [c for c in plan if c[1] in keep]
    return plan


# =============================================================================== one case
def final_at_bound_names(d, tol=1e-3):
    """Free parameters of the final fit within ``tol`` of their scaled range from a bound that is
    neither an effect's off value nor a physical limit (computed here from the fit records, so the
    check does not depend on the report's own audit)."""
    if d.final is None or d.verdict in ("none", "unexplained"):
        return []
    out = []
    for fp in d.final.free:
        v = d.final.values[fp.name]
        lo, hi = fp.z_bounds
        z = float(fp.to_z(v)) if (fp.scale == "linear" or v != 0) else lo
        for side, frac, bound in (("lower", (z - lo) / (hi - lo), fp.lower), ("upper", (hi - z) / (hi - lo), fp.upper)):
            if frac > tol:
                continue
            if "." in fp.name and not fp.name.startswith("laws."):
                e, pn = fp.name.split(".", 1)
                par = LIBRARY[e].parameter(pn) if e in LIBRARY else None
                if par is not None and (bound == par.off or side in getattr(par, "limits", ())):
                    continue
            out.append(fp.name)
    return out


def summarise(d, *, generator, label, expected, lam, detectable, out_of_library, dt, level=""):
    """The few numbers a table needs (picklable)."""
    declared = {frozenset((a, b)) for a, b, _ in d.confusable}
    fab = final_at_bound_names(d)
    final_at_bound = bool(fab)
    at_bound_said = all(n in d.message for n in fab) and "bound" in d.message
    return dict(generator=generator, label=label, level=level, expected=sorted(expected), lam=lam,
                detectable=detectable, oo=out_of_library, verdict=d.verdict, named=sorted(d.named),
                declared=declared, t=dt, gap_shrink=gap_shrink(d),
                cost_ratio=d.gap_before["cost"] / d.gap_after["cost"],
                final_at_bound=final_at_bound, at_bound_said=at_bound_said, at_bound_params=fab,
                cost_warning=getattr(d, "cost_warning", "") or "")


def run_case(item):
    gen, label, key = item
    if gen == "library":
        idx, level = key
        rng = np.random.default_rng(np.random.SeedSequence(SEALED, spawn_key=(idx,)))
        data, exact, effects = library_case(label, level, rng)
        lam = library_noncentrality(exact) if effects else 0.0
        t0 = time.perf_counter()
        d = diagnose(data, P, kind="actuator", free=FREE, alpha=ALPHA, seed=idx)
        dt = time.perf_counter() - t0
        expected = [e for e in effects if e in LIBRARY]
        return summarise(d, generator=gen, label=label, expected=expected if label != "out_of_library" else [],
                         lam=lam, detectable=lam >= DETECTABLE, out_of_library=label == "out_of_library",
                         dt=dt, level=level)
    import independent_generator as ig

    sweep, truth = ig.make_case(key, label, workflow_free=WORKFLOW_FREE_GENERATOR)
    base = IPMCParameters.from_dict(dict(truth["library_start"]))
    t0 = time.perf_counter()
    d = diagnose(sweep, base, kind="actuator", free=FREE_INDEPENDENT, alpha=ALPHA, seed=key)
    dt = time.perf_counter() - t0
    if truth["lam_each_baseline"]:
        det = min(truth["lam_each_baseline"].values()) >= DETECTABLE
    else:
        det = (truth["lam_baseline"] or 0.0) >= DETECTABLE
    if truth["lam_each_workflow"]:
        det_w = min(truth["lam_each_workflow"].values()) >= DETECTABLE
    else:
        det_w = (truth["lam_workflow"] or 0.0) >= DETECTABLE
    r = summarise(d, generator=gen, label=label, expected=truth["expected"], lam=truth["lam_baseline"] or 0.0,
                  detectable=det, out_of_library=truth["out_of_library"], dt=dt)
    r["detectable_workflow"] = det_w
    return r


def run_all(plan, workers: int):
    rows = []
    t_all = time.perf_counter()
    if workers > 1:
        from multiprocessing import get_context

        with get_context("spawn").Pool(workers) as pool:
            it = pool.imap(run_case, plan)
            for i, r in enumerate(it):
                rows.append(r)
                _line(i, len(plan), r)
    else:
        for i, item in enumerate(plan):
            rows.append(run_case(item))
            _line(i, len(plan), rows[-1])
    print(f"total {time.perf_counter() - t_all:.0f} s wall for {len(plan)} diagnoses ({workers} worker(s))")
    return rows


def _line(i, n, r):
    print(f"[{i + 1:3d}/{n}] {r['generator'][:3]} {r['level']:8s} {r['label']:45s} λ={r['lam']:9.1f} -> "
          f"{outcome(r):45s} {r['t']:5.1f} s" + (" [at bound]" if r["final_at_bound"] else ""), flush=True)


# =============================================================================== scoring
def outcome(r):
    if r["verdict"] in ("named", "at_bound"):
        return ("AT BOUND " if r["verdict"] == "at_bound" else "") + "+".join(r["named"])
    if r["verdict"] == "ambiguous":
        return "ambiguous[" + ",".join(r["named"]) + "]"
    return r["verdict"]


def correct(r, confident_only=True):
    """Exact name(s), or ambiguous among names the report itself declares confusable with a true one."""
    truth = r["expected"]
    if not truth:
        return False
    if r["verdict"] == "named" or (r["verdict"] == "at_bound" and not confident_only):
        return r["named"] == truth
    if r["verdict"] == "ambiguous":
        # every true effect among the names, every other name declared confusable with a true one
        return all(t in r["named"] for t in truth) and all(
            any(frozenset((t, o)) in r["declared"] for t in truth) for o in r["named"] if o not in truth)
    return False


def _rate(k, n):
    lo, hi = wilson(k, n)
    return f"{k}/{n}" + (f" = {k / n:.2f} (95 % Wilson [{lo:.2f}, {hi:.2f}])" if n else "")


def report(rows, title):
    if not rows:
        return
    print(f"\n################ {title} ################")
    singles = [r for r in rows if len(r["expected"]) == 1 and not r["oo"]]
    pairs = [r for r in rows if len(r["expected"]) == 2]
    nulls = [r for r in rows if r["label"] == "none"]
    oo = [r for r in rows if r["oo"]]
    print("\n=== Confusion table (truth -> outcome counts; '*' marks detectable cases' outcomes) ===")
    for lab in sorted({r["label"] for r in rows}, key=lambda s: (s != "none", "+" in s, s)):
        rr = [r for r in rows if r["label"] == lab]
        cnt = Counter(outcome(r) + ("*" if r["detectable"] else "") for r in rr)
        print(f"  {lab:45s} " + ", ".join(f"{k} {v}" for k, v in sorted(cnt.items(), key=lambda kv: -kv[1])))
    k = sum(r["verdict"] in ("named", "ambiguous", "at_bound") for r in nulls)
    k2 = sum(r["verdict"] != "none" for r in nulls)
    print(f"\n=== False positives on null data (nominal α = {ALPHA}) ===\n  a name (named/ambiguous/at bound): "
          f"{_rate(k, len(nulls))}\n  any verdict but 'none': {_rate(k2, len(nulls))}")
    det = [r for r in singles if r["detectable"]]
    det_w = [r for r in singles if r.get("detectable_workflow", r["detectable"])]
    print(f"\n=== Naming accuracy, single library effects ===\n  detectable (λ ≥ {DETECTABLE:g}), confident name: "
          f"{_rate(sum(correct(r) for r in det), len(det))}\n  detectable after refitting the workflow's own free "
          f"set (κe too), confident name: {_rate(sum(correct(r) for r in det_w), len(det_w))}"
          f"\n  detectable, incl. 'at bound' names: "
          f"{_rate(sum(correct(r, False) for r in det), len(det))}\n  all single cases: "
          f"{_rate(sum(correct(r) for r in singles), len(singles))}")
    wrong = [r for r in singles if r["verdict"] in ("named", "ambiguous") and not correct(r)]
    undeclared = [r for r in wrong if not all(frozenset((r["expected"][0], n)) in r["declared"]
                                              for n in r["named"] if n != r["expected"][0]) or r["expected"][0] not in r["named"]]
    named_wrong = [r for r in wrong if r["verdict"] == "named"]
    print(f"  wrong names: {len(wrong)} (confident, verdict 'named': {len(named_wrong)}; 'ambiguous' lists naming a "
          f"candidate the report does not declare confusable with the truth, or missing it: {len(wrong) - len(named_wrong)})"
          f"; not between pairs the report declares confusable: {len(undeclared)}")
    for r in wrong:
        print(f"    truth {r['label']:28s} -> {outcome(r)}" + (f" {r['named']}" if r["verdict"] == "ambiguous" else "")
              + f" (λ={r['lam']:.0f})")
    for r in det:
        if not correct(r) and r not in wrong:
            print(f"    missed (detectable) {r['label']:28s} λ={r['lam']:.0f} -> {outcome(r)}")
    if pairs:
        dp = [r for r in pairs if r["detectable"]]
        dpw = [r for r in pairs if r.get("detectable_workflow", r["detectable"])]
        print(f"\n=== Two hidden effects ===\n  both named (all): {_rate(sum(correct(r) for r in pairs), len(pairs))}"
              f"\n  both named (each detectable on top of the other): {_rate(sum(correct(r) for r in dp), len(dp))}"
              f"\n  the same, detectable after refitting the workflow's own free set (κe too): "
              f"{_rate(sum(correct(r) for r in dpw), len(dpw))}"
              f"\n  of those, named exactly (verdict 'named'): {_rate(sum(r['verdict'] == 'named' and correct(r) for r in dpw), len(dpw))}")
        for r in pairs:
            if not correct(r):
                print(f"    {r['label']:45s} -> {outcome(r)}" + ("" if r["detectable"] else " (not detectable)"))
    if oo:
        c = Counter(r["verdict"] for r in oo)
        vis = [r for r in oo if r["verdict"] != "none"]
        conf = [r for r in oo if r["verdict"] == "named"]
        print("\n=== Out of library ===\n  outcomes: " + ", ".join(f"{k} {v}" for k, v in c.items())
              + f"\n  unexplained among all: {_rate(sum(r['verdict'] == 'unexplained' for r in oo), len(oo))}"
              f"\n  unexplained among those not 'none': {_rate(sum(r['verdict'] == 'unexplained' for r in vis), len(vis))}"
              f"\n  confident wrong names: {len(conf)}" + "".join(f"\n    {r['label']} -> {outcome(r)}" for r in conf))
    down = [r for r in rows if r["verdict"] == "at_bound" and r["expected"] and r["named"] == r["expected"]]
    print(f"\n=== Correct names downgraded to 'at bound': {len(down)} ===")
    for r in down:
        print(f"    {r['label']:45s} -> {outcome(r)}; bound: {r.get('at_bound_params', [])}")
    hidden = [r for r in rows if r["verdict"] == "named" and r["final_at_bound"] and not r["at_bound_said"]]
    print(f"\n=== Verdicts resting on a parameter at its bound without saying so: {len(hidden)} ===")
    ok = [r for r in rows if correct(r)]
    if ok:
        cr = np.array([r["cost_ratio"] for r in ok])
        gs = np.array([r["gap_shrink"] for r in ok])
        print(f"\n=== Gap shrink (correctly named cases, n = {len(ok)}) ===\n  weighted cost before/after: "
              f"median {np.median(cr):.3g}, min {cr.min():.3g}; excess-cost ratio median {np.median(gs):.3g}, "
              f"share ≥ 5× {np.mean(gs >= 5):.2f}")
    warn = Counter(r["cost_warning"].split(":")[0] for r in rows if r["cost_warning"])
    if warn:
        print("\n=== Cost-vs-noise warnings: " + ", ".join(f"{k} {v}" for k, v in warn.items()) + " ===")
    ts = np.array([r["t"] for r in rows])
    print(f"\n=== Time per diagnosis: mean {ts.mean():.1f} s, median {np.median(ts):.1f} s, max {ts.max():.1f} s "
          f"(n = {ts.size}, wall per process on a shared 2-core machine) ===")


def real_data():
    print("\n=== Printed seed 000 35 °C sensor model as data (10-100 Hz, 40 lines, σ = 1 % per line) ===")
    from inversion.examples import seed000_sensor_35c

    tf = seed000_sensor_35c()
    f = np.logspace(1, 2, 40)
    H = np.array([complex(tf(2j * np.pi * x)) for x in f])
    n = f.size
    data = FrequencySweep(np.full(n, 35.0), f, H, np.full(n, 0.01 * 20 / math.log(10)), np.full(n, math.degrees(0.01)),
                          "tip_displacement", "mm", "current", "uA", {"source": "seed 000 printed 35 C model"})
    for set_name in ("seed000_sensor", "seed000_sensor_dev"):
        try:
            ps = get_parameter_set(set_name)
        except Exception as exc:  # pragma: no cover - set provided by another module
            print(f"  {set_name}: unavailable ({exc})")
            continue
        d = diagnose(data, ps, kind="sensor", free=("a0", "d", "kappa_e"), seed=0)
        print(f"  base {set_name}, free a0, d, kappa_e: verdict {d.verdict} {d.named}")
        print(f"    {d.message}")
        print(f"    cost {d.gap_before['cost']:.4g} -> {d.gap_after['cost']:.4g} (expected {d.gap_before['expected_cost']:.4g}); "
              f"RMS {d.gap_before['rms_db'][0]:.2f} dB / {d.gap_before['rms_deg'][0]:.1f}° -> "
              f"{d.gap_after['rms_db'][0]:.2f} dB / {d.gap_after['rms_deg'][0]:.1f}°")
        top = sorted(d.candidates.values(), key=lambda c: -c.lr)[:3]
        print("    top candidates: " + "; ".join(f"{c.name} LR {c.lr:.3g} {c.values}" for c in top))

    print("\n=== Seed 002 width series (W = 4, 2, 1, 0.5 mm) ===")
    print("  (seed 002 prints no width data; (a) the model itself at each width vs the 4 mm calibration;")
    print("   (b) strips in water: Sader's viscous load vs a model holding only the constant added mass)")
    f2 = np.logspace(-1, 1.7, 30)
    for W in (4e-3, 2e-3, 1e-3, 0.5e-3):
        pw = P.replace(W=W)
        noise = MagnitudePhaseNoise(0.25, 1.5)
        data_a = synthesize_sweep(EffectModel(pw, "actuator"), "M", f2, [26.85], noise, seed=int(W * 1e5))
        da = diagnose(data_a, P, kind="actuator", free=("alpha0", "d", "xi"), seed=1)
        # (b) a bare strip (2000 kg/m³) in water with Sader's load; the user's model holds the inviscid
        # added mass π ρ_f W²/4 per length in its density (what a calibration in water at one width gives)
        water = {"viscous_load": math.sqrt(997.0 * 0.85e-3), "log10_viscosity": math.log10(0.85e-3 / 997.0),
                 "viscosity_energy": 16e3}
        bare = pw.replace(rho=2000.0)
        data_b = synthesize_sweep(EffectModel(bare, "actuator", {"viscous_fluid": water}), "M", f2, [26.85], noise,
                                  seed=int(W * 1e5) + 1)
        db = diagnose(data_b, bare.replace(rho=2000.0 + 1000.0 * math.pi * W / (8 * P.h)), kind="actuator",
                      free=("alpha0", "d", "xi"), seed=1)
        fitted = db.final.values.get("viscous_fluid.viscous_load") if db.final else None
        print(f"  W = {W * 1e3:3.1f} mm: (a) model at W vs 4 mm set: {da.verdict} (best LR "
              f"{max(c.lr for c in da.candidates.values()):.2g}, threshold {da.threshold:.2g}); "
              f"(b) bare strip in water (Sader), model with constant added mass: {db.verdict} {db.named}"
              + (f" √(ρ_f η) = {fitted:.3g} kg m⁻² s^-½ (water {math.sqrt(997.0 * 0.85e-3):.3g})" if fitted is not None else "") + f"; cost {db.gap_before['cost']:.4g} -> "
              f"{db.gap_after['cost']:.4g}")




def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--generator", choices=("library", "independent", "both"), default="both")
    ap.add_argument("--n-per-label", type=int, default=2, help="independent: cases per label (default 2)")
    ap.add_argument("--null", type=int, default=12, help="independent: null cases in all (default 12)")
    ap.add_argument("--first-seed", type=int, default=0,
                    help="independent: first case seed (seeds 0-63 were looked at while developing; use e.g. "
                         "1000 for held-out cases)")
    ap.add_argument("--labels", help="independent: only these labels, comma-separated (or the groups pairs, "
                    "singles, oo, none), with the seeds they have in the full plan")
    ap.add_argument("--library-reps", type=int, default=1, help="library: cases per effect and noise level")
    ap.add_argument("--library-null", type=int, default=0,
                    help="library: extra null cases (noise levels in turn; seeds apart from the main plan)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--real-only", action="store_true", help="only the published-model runs")
    ap.add_argument("--no-real", action="store_true", help="skip the published-model runs")
    args = ap.parse_args(argv)
    if not args.real_only:
        plan = []
        if args.generator in ("independent", "both"):
            plan += independent_plan(args.n_per_label, args.null, args.first_seed, args.labels)
        if args.generator in ("library", "both"):
            plan += [(g, lab, (i, lev)) for i, (g, lab, lev) in enumerate(library_plan(args.library_reps))]
            levels = list(NOISE)
            plan += [("library", "none", (10_000 + k, levels[k % 3])) for k in range(args.library_null)]
        rows = run_all(plan, args.workers)
        report([r for r in rows if r["generator"] == "library"], "library generator (the library's own effects)")
        report([r for r in rows if r["generator"] == "independent"], "independent generator (tests/discrepancy)")
    if not args.no_real:
        real_data()


if __name__ == "__main__":
    main()
