"""Blind detection of seed 000's measurement-chain elements by the discrepancy workflow (issue 16).

    python3 tests/benchmarks/bench_chain_detection.py                    # both generators (~6 min)
    python3 tests/benchmarks/bench_chain_detection.py --n-per-label 1 --null 4 --generator independent

Cases: a seed 000 sensor (18 × 6.5 × 0.21 mm, development polymer values at 35 °C) with a0, d, κe
drawn ×/÷ up to 1.35 from the user's starting set, 31 lines 10-100 Hz, complex relative noise
0.5-2 % per line (σ given with the data), one hidden chain element of random size (or none, or one
out of the library):

``library``      :class:`physmodel.effects.EffectModel` with a library chain effect
                 (time_delay, amplifier_bandwidth, laser_lag, ac_coupling, fixture_joint,
                 tip_driven_beam, transimpedance); out of library: ``fixture_resonance`` (a notch).
``independent``  tests/discrepancy/independent_sensor.py: its own strip, its own chain elements
                 (a beam boundary-value problem, the op-amp node equations, ...) in its own
                 parametrisation; out of library: a gain ripple and a notch.

The workflow (``diagnose``) frees a0, d, κe and tests the seven chain effects as candidates
(null_draws 1000 linearised Monte Carlo draws, null_refits 2 full-refit bootstrap draws for the
nonlinearity correction of the threshold; both options).

Thresholds, fixed before any result was seen (not tuned):
- detectable: the baseline refitted to the noiseless data keeps λ = 2·cost ≥ 25 (issue 11's level;
  library: physmodel's own fit; independent: the generator's own fit);
- distinguishable (an oracle independent of ``diagnose``, computed before it runs): every
  candidate fitted noiselessly to the case's noiseless data (``fit_parameters`` on the library
  model, base a0, d, κe free, candidate bounds, several starts incl. the truth), and the truth beats
  every other candidate by Δλ ≥ 25;
- the workflow's own rule for ``ambiguous``: Vuong's test at the user's α = 0.05 (two-sided,
  z_crit = 1.96; see physmodel.estimation.discrepancy).

Reported per generator, each with a 95 % Wilson interval: on detectable cases with a hidden library
element, the outcome: named exactly; ``ambiguous`` listing the truth; ``at_bound`` (truth / other);
a wrong confident name (must be ≈ 0); ambiguous without the truth; unexplained; none — and
"exact or ambiguous among declared-confusable pairs" (the issue's goal: confusions only between
pairs the report declares confusable); naming on the oracle-distinguishable cases; FPR on null
data; out of library -> unexplained; wrong confident names over all cases; time per diagnosis.

Measured (``python3 tests/benchmarks/bench_chain_detection.py``, defaults; the machine was shared,
load ≈ 6 on 2 cores, so the per-diagnosis times are inflated — see the paired timing below):

=====================================  ===================  ===================  ===================  ===================
outcome (detectable cases)             library, before      library, after       independent, before  independent, after
=====================================  ===================  ===================  ===================  ===================
named exactly                          7/15                 7/15                 5/11                 5/11
ambiguous listing the truth            3/15                 8/15                 2/11                 6/11
at_bound naming the truth / other      1/15, 4/15           0/15, 0/15           2/11, 2/11           0/11, 0/11
wrong confident name                   0/15                 0/15                 0/11                 0/11
exact or ambiguous among declared      10/15 = 67 %         15/15 = 100 %        7/11 = 64 %          11/11 = 100 %
  (95 % Wilson)                        (42-85 %)            (80-100 %)           (35-85 %)            (74-100 %)
distinguishable cases / named exactly  6 / 6                6 / 6                5 / 4                5 / 5
FPR on null data (anything named)      0/8                  1/8                  0/8                  0/8
out of library -> unexplained          3/3                  3/3                  4/4                  4/4
wrong confident names, all cases       1/32                 2/32                 1/33                 1/33
median / max s per diagnosis (loaded)  12.2 / 29.8          11.1 / 22.9          6.3 / 16.0           10.9 / 18.3
=====================================  ===================  ===================  ===================  ===================

"before" = commit df39d69 (candidate refits from the baseline optimum only, ambiguity by an AIC
window of 6 plus first-order signature cosine ≥ 0.9, fixture_joint skipped when its tangent
signature vanished) run with this script; "after" = this branch at its last commit (985 s).  The docstring's earlier table
(commit b6611f9, older reporting) had library 8/15, independent 5/11 named exactly.

Paired timing (same loaded machine, 3 interleaved runs of 4 fixed independent cases — opamp 6,
laser 7, joint 13, none 21 — with the bench's diagnose settings, whole process): after 12.0 s vs
before 3.3 s per diagnosis, ratio 3.56 (3.45-3.64).  The cost is the null bootstrap refits, which
now repeat the data's full multi-start search (≈ 5.5 of ≈ 9 s on an idle core), then the second
base start of the candidate refits and the cross-fits.  Within the issue's 60 s per diagnosis.

What the figures say: 9 of the 15 (library) and 6 of the 11 (independent) detectable cases are not
distinguishable in 10-100 Hz at all — a laser lag and a strip resonance above the band differ by
Δλ < 0.02 noiselessly, one amplifier pole reproduces the transimpedance circuit to Δλ < 3e-4, the
fixture joint and the strip resonance by Δλ 0.3-14 — so "named exactly ≥ 90 % of detectable" cannot
be reached by any honest procedure on these data; on the distinguishable cases naming is 6/6 and
5/5, and every other detectable case is now ``ambiguous`` listing the truth with the pair declared
confusable (by the data and by the noiseless cross-fit), not ``at_bound`` on the wrong element.
The wrong confident names left are in non-detectable cases (λ 0.7-9: ``tip_driven_beam``) and one
null case (library seed 23): the multi-start finds a resonance basin (LR 7.7 from the user's start,
0.08 from the baseline optimum) that the 2-draw bootstrap correction of the threshold (ratio 1.09)
does not see: a look-elsewhere effect of a free resonance frequency, which the linearised null
(secant signature, LR 0) misses.  1/16 null cases over both generators is consistent with α = 5 % (Wilson
1-28 %), but the threshold for such candidates is the open problem.

Held-out run after the look-elsewhere scan of the null (issue 16, main at 3ffe369: the null takes the
supremum of the linearised LR over a grid of the parameters that act only once an effect is on —
a resonance's frequency and damping — and a candidate that beats the baseline triggers a baseline
refit from its base values), on seeds nobody had run, 24 nulls per generator:
``python3 tests/benchmarks/bench_chain_detection.py --first-seed 1000 --null 24 --workers 2`` (756 s):

=====================================  =========================  =========================
outcome                                library                    independent
=====================================  =========================  =========================
detectable cases: named exactly        4/14                       7/16
  ambiguous listing the truth          9/14                       8/16
  at_bound naming the truth            1/14 (λ 27, joint)         1/16 (λ 37, joint)
  wrong confident name                 0/14                       0/16
  exact or ambiguous among declared    13/14 = 93 % (69-99 %)     15/16 = 94 % (72-99 %)
distinguishable (oracle) / named       4 / 4                      7 / 7
FPR on null data (anything named)      0/24 (0-14 %)              0/24 (0-14 %)
  any verdict but 'none'               1/24 (unexplained)         1/24 (unexplained)
out of library -> unexplained          3/3                        4/4
wrong confident names, all cases       0/48                       0/49
median / max s per diagnosis           12.5 / 23.3                11.5 / 19.7
=====================================  =========================  =========================

Every detectable case the workflow did not name exactly is one the oracle finds indistinguishable
in 10-100 Hz (margins 9e-6 to 4.8 noiseless λ against the runner-up, a strip resonance above the
band or one amplifier pole), and the report lists the truth with the pair declared confusable.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections import Counter
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):     # one thread per diagnosis
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402
from _stats import wilson_text  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "tests" / "discrepancy")]

import independent_sensor as isn

from physmodel import get_parameter_set
from physmodel.data.sweep import FrequencySweep
from physmodel.effects import EffectModel
from physmodel.estimation.discrepancy import diagnose
from physmodel.estimation.lsq import fit_parameters
from scenarios.steps_chain import CANDIDATES, physics_free

DETECTABLE = 25.0
#: A detectable case is distinguishable when the truth beats every other candidate by this much
#: (noiseless λ = 2·cost); fixed a priori (issue 11's detectability level), not from results.
DISTINGUISHABLE = 25.0
T_C = 35.0
LIB_OF = {k: v[0] for k, v in isn.EFFECT_SPECS.items()}


def start_set():
    return get_parameter_set("seed000_sensor_dev", T_ref=T_C + 273.15)


def library_effect(name: str, v: dict) -> tuple:
    """The independent generator's physical sizes in the library's parametrisation."""
    tau = lambda f: 1.0 / (2 * math.pi * f)
    if name == "amplifier":
        return "amplifier_bandwidth", {"time_constant": tau(v["f_a"]), "second_time_constant": tau(v["f_a"] * v["ratio"])}
    if name == "delay":
        return "time_delay", {"delay": v["tau"]}
    if name == "laser":
        return "laser_lag", {"time_constant": tau(v["f_l"])}
    if name == "ac_coupling":
        return "ac_coupling", {"corner_hz": v["f_c"]}
    if name == "joint":
        return "fixture_joint", {"time_constant": tau(v["f_j"]), "damping": v["zeta"]}
    if name == "slit_beam":
        return "tip_driven_beam", {"time_constant": tau(v["f_cp"]), "damping": v["zeta"]}
    if name == "opamp":
        return "transimpedance", {"unity_gain_time": tau(v["gbw"]), "inverse_dc_gain": 1.0 / isn.A0}
    if name == "notch":
        return "fixture_resonance", {"frequency_hz": v["f_n"], "depth": v["depth"], "damping": v["zeta"]}
    raise ValueError(name)


def library_case(seed: int, label: str):
    """(sweep, truth) from EffectModel: same draws of size and base as the independent generator."""
    rng = np.random.default_rng([0x11B, seed])
    p0 = start_set()
    base = p0.replace(**{k: getattr(p0, k) * math.exp(rng.uniform(-1, 1) * math.log(1.35))
                         for k in ("a0", "d", "kappa_e")})
    eff = {}
    if label != "none":
        eff = dict([library_effect(label, isn.draw_effect(label, rng))])
    f = isn.FREQUENCIES_HZ
    H1 = EffectModel(base, "sensor", eff).frequency_response(f, [T_C])["S"][0, 0] * 1e3
    sig = rng.uniform(*isn.NOISE_RANGE) / math.sqrt(2)
    noisy = H1 * (1 + sig * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)))
    mk = lambda H: FrequencySweep(np.full(f.size, T_C), f, H, np.full(f.size, 20 / math.log(10) * sig),
                                  np.full(f.size, math.degrees(sig)), "tip_displacement", "mm", "current", "uA")
    lam = 0.0
    if eff:
        exact = mk(H1)
        pm = EffectModel(p0, "sensor", {}).predictor(exact, "S").many
        r = fit_parameters(exact, None, physics_free(p0, ["a0", "d", "kappa_e"], math.copysign(1, p0.a0)),
                           predict_many=pm, starts=2, seed=0, max_nfev=400, identify=False)
        lam = 2 * r.cost
    exp = [] if label == "none" or LIB_OF[label] is None else [LIB_OF[label]]
    return mk(noisy), {"label": label, "expected": exp, "out_of_library": label in isn.OUT_OF_LIBRARY,
                       "lam_baseline": lam, "effects": eff, "noiseless": mk(H1),
                       "true_base": {k: getattr(base, k) for k in ("a0", "d", "kappa_e")}}


def independent_oracle_inputs(sweep, truth):
    """The independent case's noiseless sweep, true base (library names) and truth in library terms."""
    f = sweep.frequency_hz
    H = isn.response(truth["base"], truth["effects"], f) * 1e3
    noiseless = FrequencySweep(sweep.temperature_c, f, H, sweep.magnitude_std_db, sweep.phase_std_deg,
                               sweep.input_name, sweep.input_unit, sweep.output_name, sweep.output_unit)
    lf = isn.library_fields(truth["base"])
    eff = dict(library_effect(n, v) for n, v in truth["effects"].items() if LIB_OF.get(n))
    return dict(truth, noiseless=noiseless, true_base={k: lf[k] for k in ("a0", "d", "kappa_e")}, effects=eff)


def oracle(truth, candidates):
    """Noiseless fits of every candidate (base a0, d, κe free, candidate bounds of the library, no
    plausible-range walls) to the case's noiseless data, decided before diagnose runs and without it.

    Starts per candidate: the user's start set with the effect at its typical size (plus 2 Latin-
    hypercube starts), at 1 % of its reach from off, the true base with the typical size, and for the
    true candidate the true values.  Returns ``{candidate: λ = 2·cost}`` and ``distinguishable``:
    the truth beats every other candidate by Δλ ≥ DISTINGUISHABLE."""
    from physmodel.effects import LIBRARY
    from physmodel.estimation.records import FreeParameter

    p0 = start_set()
    data = truth["noiseless"]
    pm = EffectModel(p0, "sensor", {}).predictor(data, "S").many
    sign = math.copysign(1, p0.a0)
    lam = {}
    for c in candidates:
        cp = LIBRARY[c].candidate_parameters(p0)
        tv = truth["effects"].get(c, {})
        eff_starts = [({p.name: p.typical for p in cp}, 3),
                      ({p.name: p.off + 0.01 * ((p.upper if p.upper != p.off else p.lower) - p.off) for p in cp}, 1)]
        base_starts = [None, truth["true_base"]]
        if tv:
            eff_starts.append(({p.name: tv.get(p.name, p.off) for p in cp}, 1))
        best = math.inf
        for bs in base_starts:
            for es, n in eff_starts:
                fr = physics_free(p0, ["a0", "d", "kappa_e"], sign, bs)
                fr += [FreeParameter(f"{c}.{p.name}", p.lower, p.upper, "linear",
                                     float(np.clip(es[p.name], p.lower, p.upper))) for p in cp]
                r = fit_parameters(data, None, fr, predict_many=pm, starts=n, seed=0, max_nfev=400, identify=False)
                best = min(best, 2 * r.cost)
        lam[c] = best
    t = truth["expected"][0] if truth["expected"] else None
    margin = min((v for c, v in lam.items() if c != t), default=math.inf) - lam.get(t, math.inf) if t else -math.inf
    return {"lambda": lam, "margin": margin, "distinguishable": bool(t and margin >= DISTINGUISHABLE)}


def run_case(sweep, truth, args):
    cands = [c for c in CANDIDATES if c not in args.exclude]
    det = truth["lam_baseline"] >= DETECTABLE
    orc = oracle(truth, cands) if (truth["expected"] and det and not args.no_oracle) else None   # before diagnose
    p0 = start_set()
    t = time.perf_counter()
    d = diagnose(sweep, p0, kind="sensor", free=physics_free(p0, ["a0", "d", "kappa_e"], math.copysign(1, p0.a0)),
                 candidates=cands, null_draws=args.null_draws, null_refits=args.null_refits, baseline_starts=2, seed=1)
    return {"label": truth["label"], "expected": truth["expected"], "lam": truth["lam_baseline"],
            "detectable": det, "oo": truth["out_of_library"], "oracle": orc,
            "declared": {frozenset(x[:2]) for x in d.confusable},
            "verdict": d.verdict, "named": sorted(d.named), "dt": time.perf_counter() - t}


def outcome(r) -> str:
    """One of: exact, ambiguous_with_truth, at_bound_truth, at_bound_other, wrong_name,
    ambiguous_without_truth, unexplained, none (for cases with a hidden library element)."""
    v, named, exp = r["verdict"], r["named"], r["expected"]
    if v == "named":
        return "exact" if named == exp else "wrong_name"
    if v == "ambiguous":
        return "ambiguous_with_truth" if set(exp) <= set(named) else "ambiguous_without_truth"
    if v == "at_bound":
        return "at_bound_truth" if named == exp else "at_bound_other"
    return v


def report(rows, name):
    print(f"\n=== {name} generator: {len(rows)} cases, time per diagnosis median "
          f"{np.median([r['dt'] for r in rows]):.1f} s, max {max(r['dt'] for r in rows):.1f} s ===")
    for lab in sorted({r["label"] for r in rows}):
        rr = [r for r in rows if r["label"] == lab]
        cnt = Counter(f"{r['verdict']}:{'+'.join(r['named']) or '-'}" + ("*" if r["detectable"] else "") for r in rr)
        print(f"  {lab:14s} " + ", ".join(f"{k} ×{v}" for k, v in cnt.items()))
    det = [r for r in rows if r["expected"] and r["detectable"]]
    oc = Counter(outcome(r) for r in det)
    n = len(det)
    print(f"  detectable (λ ≥ {DETECTABLE:g}), {n} cases:")
    for k in ("exact", "ambiguous_with_truth", "at_bound_truth", "at_bound_other", "wrong_name",
              "ambiguous_without_truth", "unexplained", "none"):
        print(f"    {k:24s} {wilson_text(oc.get(k, 0), n)}")
    amb_decl = sum(outcome(r) == "ambiguous_with_truth" and all(
        frozenset((r["expected"][0], o)) in r["declared"] for o in r["named"] if o != r["expected"][0]) for r in det)
    print(f"    exact or ambiguous-with-truth among declared-confusable pairs (issue goal): "
          f"{wilson_text(oc.get('exact', 0) + amb_decl, n)}")
    dist = [r for r in det if r["oracle"] is not None and r["oracle"]["distinguishable"]]
    print(f"  distinguishable by the oracle (noiseless Δλ ≥ {DISTINGUISHABLE:g} to every other candidate): "
          f"{len(dist)} of {sum(r['oracle'] is not None for r in det)}; named exactly: "
          f"{wilson_text(sum(outcome(r) == 'exact' for r in dist), len(dist))}; wrong confident names: "
          f"{sum(outcome(r) == 'wrong_name' for r in dist)}")
    for r in det:
        if outcome(r) != "exact":
            o = r["oracle"]
            print(f"    {r['label']:12s} λ = {r['lam']:.0f} -> {r['verdict']} {r['named']}"
                  + (f"; oracle margin {o['margin']:.3g} ({min(((v, c) for c, v in o['lambda'].items() if c not in r['expected']), default=(0, '-'))[1]})"
                     if o else ""))
    und = [r for r in rows if r["expected"] and not r["detectable"]]
    nul = [r for r in rows if r["label"] == "none"]
    oo = [r for r in rows if r["oo"]]
    wrong_all = [r for r in rows if r["verdict"] == "named" and r["named"] != r["expected"]]
    print(f"  not detectable (λ < {DETECTABLE:g}): {len(und)} cases; named correctly anyway "
          f"{sum(r['named'] == r['expected'] and r['verdict'] == 'named' for r in und)}; wrong confident names "
          f"{sum(outcome(r) == 'wrong_name' for r in und)}")
    print(f"  FPR on null data (anything named, any verdict naming an effect): "
          f"{wilson_text(sum(bool(r['named']) for r in nul), len(nul))}; any verdict but 'none': "
          f"{wilson_text(sum(r['verdict'] != 'none' for r in nul), len(nul))}")
    print(f"  out of library -> unexplained: {wilson_text(sum(r['verdict'] == 'unexplained' for r in oo), len(oo))}; "
          f"-> none: {sum(r['verdict'] == 'none' for r in oo)}; confident name: "
          f"{sum(r['verdict'] == 'named' for r in oo)}; ambiguous/at bound: "
          f"{sum(r['verdict'] in ('ambiguous', 'at_bound') for r in oo)}")
    print(f"  wrong confident names over all {len(rows)} cases (detectable, undetectable, null, out of library): "
          f"{wilson_text(len(wrong_all), len(rows))}")
    return {"outcomes": dict(oc), "n_detectable": n, "exact": (oc.get("exact", 0), n),
            "distinguishable_exact": (sum(outcome(r) == "exact" for r in dist), len(dist)),
            "wrong": (len(wrong_all), len(rows)), "fpr": (sum(bool(r["named"]) for r in nul), len(nul)),
            "oo_unexplained": (sum(r["verdict"] == "unexplained" for r in oo), len(oo)),
            "dt_median": float(np.median([r["dt"] for r in rows])), "dt_max": float(max(r["dt"] for r in rows))}


def validate_generator():
    """The independent sensor agrees with physmodel where both model the same thing (it must, or
    the blind cases would test the generator rather than the workflow)."""
    from scipy.optimize import brentq

    from physmodel import SensorModel

    lam = brentq(lambda x: math.tan(x) - math.tanh(x), 3.5, 4.5, xtol=1e-15)
    f = isn.FREQUENCIES_HZ
    G, Z = isn.strip_sensor(isn.START, 2j * np.pi * f)
    r = SensorModel(start_set()).frequency_response(f, [T_C], quantities=("S", "Z"))
    worst = max(np.max(np.abs(G / r["S"][0, 0] - 1)), np.max(np.abs(Z / r["Z"][0, 0] - 1)))
    for n in isn.IN_LIBRARY:
        v = isn.draw_effect(n, np.random.default_rng(5), 0.7)
        le = dict([library_effect(n, v)])
        a = isn.response(isn.START, {n: v}, f)
        b = EffectModel(start_set(), "sensor", le).frequency_response(f, [T_C])["S"][0, 0]
        worst = max(worst, float(np.max(np.abs(a / b - 1))))
    print(f"generator check: tan λ = tanh λ root {lam:.15f} (module {isn.LAMBDA_CP}); independent strip and chain "
          f"vs physmodel: max relative difference {worst:.2g}")
    if abs(lam - isn.LAMBDA_CP) > 1e-12 or worst > 1e-9:
        raise SystemExit("the independent generator disagrees with physmodel: fix it before benchmarking")


def _one(item):
    """One case (a worker's unit): ``(generator, seed, label, args)`` -> the row of :func:`run_case`."""
    gen, seed, lab, args = item
    if gen == "library":
        sw, tr = library_case(seed, lab)
    else:
        sw, tr = isn.make_case(seed, lab)
        tr = independent_oracle_inputs(sw, tr)
    if set(tr["expected"]) & set(args.exclude):
        tr = dict(tr, expected=[], out_of_library=True)
    return run_case(sw, tr, args)


def _report_rows(results, items):
    rows = []
    for (gen, seed, lab, _), row in zip(items, results):
        rows.append(row)
        o = row["oracle"]
        print(f"  [{gen} {len(rows)}/{len(items)} seed {seed}] {lab:12s} λ = {row['lam']:8.1f} -> {row['verdict']} "
              f"{row['named']} ({row['dt']:.1f} s)" + (f" oracle margin {o['margin']:.3g}" if o else ""), flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--generator", choices=("both", "library", "independent"), default="both")
    ap.add_argument("--n-per-label", type=int, default=3)
    ap.add_argument("--null", type=int, default=8)
    ap.add_argument("--null-draws", type=int, default=1000)
    ap.add_argument("--first-seed", type=int, default=0, help="seed of the first case (cases use consecutive seeds)")
    ap.add_argument("--workers", type=int, default=1, help="processes (each diagnosis is single-threaded)")
    ap.add_argument("--null-refits", type=int, default=2)
    ap.add_argument("--no-oracle", action="store_true", help="skip the noiseless distinguishability oracle")
    ap.add_argument("--exclude", nargs="*", default=[], help="candidates left out (a diagnostic variant; cases "
                    "whose hidden element is left out count as out of library)")
    args = ap.parse_args(argv)
    validate_generator()
    t0 = time.perf_counter()
    labels = [lab for lab in isn.IN_LIBRARY for _ in range(args.n_per_label)]
    out = {}
    for gen in (("library", "independent") if args.generator == "both" else (args.generator,)):
        oo = ["notch"] * 3 if gen == "library" else ["gain_ripple", "notch"] * 2
        cases = labels + ["none"] * args.null + oo
        print(f"\n{gen}: candidates {[c for c in CANDIDATES if c not in args.exclude]}")
        items = [(gen, args.first_seed + i, lab, args) for i, lab in enumerate(cases)]
        if args.workers > 1:
            from multiprocessing import get_context

            with get_context("spawn").Pool(args.workers) as pool:
                rows = _report_rows(pool.imap(_one, items), items)
        else:
            rows = _report_rows(map(_one, items), items)
        out[gen] = report(rows, gen)
    print(f"\nelapsed {time.perf_counter() - t0:.0f} s")
    return out


if __name__ == "__main__":
    main()
