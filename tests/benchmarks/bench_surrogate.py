"""Benchmark of the surrogate fitters on physmodel sweeps (a script, not collected by pytest).

    python tests/benchmarks/bench_surrogate.py [--quick] [--sections 1234]

Data: every sweep is a ``physmodel`` Chen–Tan sweep (infinite-dimensional, so there is no exact
low-order answer), synthesised by :func:`generate_sweep` with
``physmodel.data.sweep.synthesize_sweep`` and seeded ``MagnitudePhaseNoise``, and handed to the fitters
through ``surrogate.from_sweep``; the noise-free truth is the same call with ``noise=None``.

Samples (``SAMPLES``):
  * seed-002 sample  — ``ActuatorModel(get_parameter_set("seed002_table3"))``, quantity "M" [mm/V]
  * seed-001 actuator — ``ActuatorModel(get_parameter_set("seed001_actuator"))`` (seed 001's
    45 x 11 x 0.3 mm strip, E and the C⁻ temperature law calibrated to the printed 19-vs-55 °C
    trend), quantity "M" [mm/V]
  * seed-001 actuator, r1' = 2 Ω — the same with ``r1_sheet=2.0`` (a labelled sensitivity case:
    lower electrode resistance)
  * seed-000 sensor  — ``SensorModel(get_parameter_set("seed000_sensor"))`` (calibrated to seed
    000's printed 35 °C model; temperature laws chosen for the published trend directions),
    quantity "S" [µA/mm]

Prints:
  1. held-out error at 35 and 45 °C (excluded from the fit): joint scheduled fit vs the
     two-stage method (papers' Levy/invfreqs first stage, and our stable-NLP first stage), with
     the floors that decide whether the goal "joint ≤ ½ two-stage" is reachable at all: the
     order-limited floor (best fit of that order to the noise-free response at the held-out
     temperature) and the joint model's own noise-induced error (delta method); then the
     joint fit's convergence over ten noise seeds;
  2. per-temperature fit error and pole stability vs scipy AAA, scikit-rf VectorFitting and a
     Levy linear least-squares fit, at equal order, with times;
  3. fit times: joint fit (10 temperatures x 60 frequencies, order 4/4, cubic schedules) vs the
     two-stage peers;
  4. order-selection tables and the papers' order / shape claims checked on the physics sweeps.
"""

from __future__ import annotations

import argparse
import importlib.util
import time
import warnings

import numpy as np

import physmodel
from physmodel.data.sweep import MagnitudePhaseNoise, synthesize_sweep
from surrogate import (
    RationalFit,
    ScheduledFit,
    from_sweep,
    levy,
    order_selection,
    relative_rms_error,
)

SEED001_TEMPS = [19.0, 21.5, 23.3, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0]
SEED000_TEMPS = [23.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 60.0, 65.0]
HELD_OUT = [35.0, 45.0]
NOISE = MagnitudePhaseNoise(0.2, 1.0)          # per line, given to the fits as std
ORDER_NOISE = MagnitudePhaseNoise(0.3, 2.0)    # order-selection protocol (as before)

# name -> (model class, parameter set, overrides, quantity)
SAMPLES = {
    "seed-002 sample": ("actuator", "seed002_table3", {}, "M"),
    "seed-001 actuator": ("actuator", "seed001_actuator", {}, "M"),
    "seed-001 actuator, r1'=2 Ω": ("actuator", "seed001_actuator", {"r1_sheet": 2.0}, "M"),
    "seed-000 sensor": ("sensor", "seed000_sensor", {}, "S"),
}
TEMPS = {"seed-000 sensor": SEED000_TEMPS}


def physics_model(sample: str, extra=None):
    kind, name, overrides, _ = SAMPLES[sample]
    params = physmodel.get_parameter_set(name, **{**overrides, **(extra or {})})
    return physmodel.ActuatorModel(params) if kind == "actuator" else physmodel.SensorModel(params)


def generate_sweep(sample: str, temperatures_c, frequency_hz, seed: int, noise=NOISE, overrides=None):
    """THE data source of this benchmark.

    Returns ``(data, truth)``: ``data = surrogate.from_sweep(synthesize_sweep(..., noise, seed))``
    (a ``FrequencyData`` carrying the noise's per-line std) and the noise-free response on the
    same lines (``synthesize_sweep(..., noise=None)``).
    """
    model = physics_model(sample, overrides)
    q = SAMPLES[sample][3]
    sweep = synthesize_sweep(model, q, frequency_hz, temperatures_c, noise, seed=seed)
    exact = synthesize_sweep(model, q, frequency_hz, temperatures_c, None)
    assert np.array_equal(sweep.frequency_hz, exact.frequency_hz)
    assert np.array_equal(sweep.temperature_c, exact.temperature_c)
    return from_sweep(sweep), exact.response


def _noise_floor(noise) -> float:
    """Relative RMS size of the noise itself (what a perfect model scores against the data)."""
    return float(np.hypot(noise.sigma_db * np.log(10) / 20, np.deg2rad(noise.sigma_deg)))


# --------------------------------------------------------------------------- 1. held-out
HELD_OUT_CASES = [  # sample, band [Hz], lines, form, zeros, poles, degree, note
    ("seed-002 sample", (0.1, 20.0), 60, "coefficients", 4, 4, 3, ""),
    ("seed-001 actuator", (0.1, 9.0), 30, "zpk", 3, 3, 2, "seed 001's model"),
    ("seed-001 actuator", (0.1, 9.0), 30, "zpk", 4, 4, 2, "order the physics needs"),
    ("seed-001 actuator", (0.1, 9.0), 30, "coefficients", 4, 4, 2, ""),
    ("seed-001 actuator, r1'=2 Ω", (0.1, 9.0), 30, "zpk", 3, 3, 2, "seed 001's model"),
    ("seed-000 sensor", (10.0, 100.0), 60, "coefficients", 4, 4, 3, "seed 000's model"),
    ("seed-000 sensor", (10.0, 100.0), 60, "coefficients", 2, 2, 3, "lowest order at the noise floor"),
    ("seed-000 sensor", (10.0, 100.0), 60, "zpk", 2, 2, 3, "lowest order at the noise floor"),
]


def _held_out_errors(model, data, truth):
    out = {}
    for temp in HELD_OUT:
        k = data.temperature_c == temp
        hm = model.frequency_response(data.frequency_hz[k], temp)
        out[temp] = (relative_rms_error(hm, truth[k]), relative_rms_error(hm, data.response[k]))
    return out


def _floors(data, truth, m, n):
    """Reference errors at each held-out temperature (against the noise-free response):

    * ``order``: best stable m/n fit to the *noise-free* response at that temperature — no
      model of this order can do better there, whatever it is fitted to (order-limited floor);
    * ``own``: m/n fit to that temperature's own *noisy* data — what measuring the held-out
      temperature would have given (noise-limited reference).
    """
    out = {}
    for temp in HELD_OUT:
        k = data.temperature_c == temp
        f = data.frequency_hz[k]
        exact = RationalFit(m, n, raise_on_failure=False).fit(f, temp, truth[k])
        own = RationalFit(m, n, raise_on_failure=False).fit_data(data.at_temperature(temp))
        out[temp] = (relative_rms_error(exact.model.frequency_response(f), truth[k]),
                     relative_rms_error(own.model.frequency_response(f), truth[k]))
    return out


def held_out_section(quick: bool):
    print("\n## 1. Held-out temperatures (35 and 45 °C excluded from the fit)\n")
    print(f"Actuators: fit on {[t for t in SEED001_TEMPS if t not in HELD_OUT]} °C (seed 001); "
          f"sensor: fit on {[t for t in SEED000_TEMPS if t not in HELD_OUT]} °C (seed 000); "
          f"log-spaced lines; noise {NOISE.sigma_db} dB / {NOISE.sigma_deg}° (given to the fit as per-line std; "
          f"noise floor of one line ≈ {_noise_floor(NOISE):.3f}).")
    print("Errors are relative RMS errors against the noise-free physics response at the held-out temperature, "
          "mean over the noise seeds (worst seed in brackets). Ratios: of the means, and of the medians. "
          "'joint ok' = joint fits that converged AND whose poles are stable on a 501-point T grid "
          "(largest pole real part over grid and seeds in brackets, rad/s). "
          "Floors (means over seeds): 'order' = best fit of this order to the noise-free response AT the held-out "
          "temperature (no model of this order does better there); 'own data' = fit of this order to the "
          "held-out temperature's own noisy data; 'joint σ' = RMS relative standard deviation of the joint "
          "model's response at the held-out temperature from its own parameter covariance (delta method, "
          "RationalModel.response_std): the noise-induced error the joint fit is expected to have. "
          "Verdict: 'met'; 'order-limited' when the order floor exceeds half the papers' two-stage error "
          "(unreachable at this order); 'noise-limited' when the joint fit's own expected noise error σ "
          "exceeds half the papers' error (reaching the goal would take beating the model's noise floor); "
          "'joint / own data' < 1 means the joint model predicts the unmeasured temperature better than a fit "
          "to that temperature's own measurement.\n")
    seeds = [1, 2] if quick else [1, 2, 3, 4, 5]
    print("| data | band [Hz] × lines | form | order | degree | T [°C] | joint | two-stage (Levy = papers') | "
          "two-stage (our NLP) | floor: order | floor: own data | joint σ (delta) | joint / papers' (mean; median) | "
          "joint / NLP two-stage (mean; median) | verdict | joint ok | joint time [s] |")
    print("|:--|:--|:--|:--|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|:--|:--:|--:|")
    summary = []
    for sample, band, nf, form, m, n, deg, note in HELD_OUT_CASES:
        f1 = np.geomspace(band[0], band[1], nf)
        temps = TEMPS.get(sample, SEED001_TEMPS)
        acc = {k: {t: [] for t in HELD_OUT} for k in ("joint", "levy", "nlp", "order", "own", "sigma")}
        n_ok, max_re, times = 0, -np.inf, []
        for seed in seeds:
            data, truth = generate_sweep(sample, temps, f1, seed)
            fit = data.select(~np.isin(data.temperature_c, HELD_OUT))
            t0 = time.perf_counter()
            res = ScheduledFit(form, m, n, deg, raise_on_failure=False).fit_data(fit)
            times.append(time.perf_counter() - t0)
            res_levy = ScheduledFit(form, m, n, deg, method="two-stage", per_temperature="levy",
                                    raise_on_failure=False).fit_data(fit)
            stab = res.model.stability_check(501)
            n_ok += bool(stab.stable and res.converged)
            max_re = max(max_re, stab.max_pole_real_part_rad_s)
            for key, model in (("joint", res.model), ("levy", res_levy.model), ("nlp", res.two_stage)):
                for temp, e in _held_out_errors(model, data, truth).items():
                    acc[key][temp].append(e[0])
            for temp, (e_order, e_own) in _floors(data, truth, m, n).items():
                acc["order"][temp].append(e_order)
                acc["own"][temp].append(e_own)
                k = data.temperature_c == temp
                rel_std = res.model.response_std(data.frequency_hz[k], temp) / np.abs(truth[k])
                acc["sigma"][temp].append(float(np.sqrt(np.mean(rel_std ** 2))))
        label = sample + (f" ({note})" if note else "")
        for temp in HELD_OUT:
            mean = {k: float(np.mean(acc[k][temp])) for k in acc}
            med = {k: float(np.median(acc[k][temp])) for k in acc}
            worst = {k: float(np.max(acc[k][temp])) for k in acc}
            r_levy, r_nlp = mean["joint"] / mean["levy"], mean["joint"] / mean["nlp"]
            q_levy, q_nlp = med["joint"] / med["levy"], med["joint"] / med["nlp"]
            if r_levy <= 0.5:
                verdict = "met"
            elif mean["order"] > 0.5 * mean["levy"]:
                verdict = f"order-limited (floor / papers' = {mean['order'] / mean['levy']:.2f})"
            elif mean["sigma"] > 0.5 * mean["levy"]:
                verdict = f"noise-limited (joint σ / papers' = {mean['sigma'] / mean['levy']:.2f})"
            else:
                verdict = "NOT met"
            verdict += f"; joint / own data = {mean['joint'] / mean['own']:.2f}"
            summary.append((label, form, m, temp, r_levy, r_nlp, q_levy, verdict))
            cells = " | ".join(f"{mean[k]:.4g} ({worst[k]:.3g})" for k in ("joint", "levy", "nlp"))
            print(f"| {label} | {band[0]:g}–{band[1]:g} × {nf} | {form} | {m}/{n} | {deg} | {temp:g} | {cells} | "
                  f"{mean['order']:.4g} | {mean['own']:.4g} | {mean['sigma']:.4g} | {r_levy:.3g}; {q_levy:.3g} | {r_nlp:.3g}; {q_nlp:.3g} | "
                  f"{verdict} | {n_ok}/{len(seeds)} ({max_re:.3g}) | {np.mean(times):.1f} |")
    n_ok = sum(r[4] <= 0.5 for r in summary)
    n_ok2 = sum(r[5] <= 0.5 for r in summary)
    n_okm = sum(r[6] <= 0.5 for r in summary)
    print(f"\nGoal 'joint error ≤ ½ two-stage (papers' Levy first stage)': met in {n_ok}/{len(summary)} rows "
          f"(ratio of means; {n_okm}/{len(summary)} by medians); against our NLP two-stage: met in "
          f"{n_ok2}/{len(summary)} rows.")
    print("Rows where it is not met (ratio of means): " + ("; ".join(
        f"{lab} {form} {m}/{m} at {t:g} °C (×{r:.2f}, {v})" for lab, form, m, t, r, _, _, v in summary if r > 0.5)
        or "none"))
    robustness(quick)


def robustness(quick: bool):
    """How often the joint fit converges, over more noise draws (the cheap seed-001 cases)."""
    seeds = range(1, 5) if quick else range(1, 11)
    print(f"\nJoint-fit convergence over noise seeds {seeds.start}–{seeds.stop - 1} (seed-001 actuator, "
          "35/45 °C held out); held-out error vs truth at 35 °C, median and worst over the seeds:\n")
    print("| data | form | order | degree | converged | median err 35 °C | worst err 35 °C | seeds not converged |")
    print("|:--|:--|:--|--:|--:|--:|--:|:--|")
    f1 = np.geomspace(0.1, 9.0, 30)
    for sample, form, m, deg in (("seed-001 actuator", "zpk", 3, 2), ("seed-001 actuator", "zpk", 4, 2),
                                 ("seed-001 actuator", "coefficients", 4, 2)):
        errs, bad = [], []
        for seed in seeds:
            data, truth = generate_sweep(sample, SEED001_TEMPS, f1, seed)
            res = ScheduledFit(form, m, m, deg, raise_on_failure=False).fit_data(
                data.select(~np.isin(data.temperature_c, HELD_OUT)))
            if not (res.converged and res.stability.stable):
                bad.append(seed)
            errs.append(_held_out_errors(res.model, data, truth)[35.0][0])
        print(f"| {sample} | {form} | {m}/{m} | {deg} | {len(errs) - len(bad)}/{len(errs)} | "
              f"{np.median(errs):.4f} | {np.max(errs):.4f} | {bad or '–'} |")


# --------------------------------------------------------------------------- 2. per temperature
def _aaa(w, h, n):
    from scipy.interpolate import AAA

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = AAA(1j * w, h, max_terms=n + 1)
    return r(1j * w), r.poles()


def _vf(f, h, n):
    import skrf
    from skrf.vectorFitting import VectorFitting

    nw = skrf.Network(frequency=skrf.Frequency.from_f(f, unit="hz"), s=h.reshape(-1, 1, 1))
    best = None
    for n_real in range(n % 2, n + 1, 2):  # every split of n poles into real and complex pairs
        vf = VectorFitting(nw)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            vf.vector_fit(n_poles_real=n_real, n_poles_cmplx=(n - n_real) // 2, init_pole_spacing="log",
                          fit_constant=True, fit_proportional=False, enforce_dc=False)
        hm = vf.get_model_response(0, 0, freqs=f)
        err = relative_rms_error(hm, h)
        if best is None or err < best[0]:
            poles = np.concatenate([vf.poles, np.conj(vf.poles[vf.poles.imag > 0])])
            best = (err, hm, poles)
    return best[1], best[2]


def _levy(w, h, m, n):
    wr = float(np.sqrt(w.min() * w.max()))
    g = float(np.exp(np.mean(np.log(np.abs(h)))))
    num, den = levy(w / wr, h / g, m, n)
    jw = 1j * w / wr
    return g * np.polyval(num[::-1], jw) / np.polyval(den[::-1], jw), wr * np.roots(den[::-1])


PER_T_CASES = [("seed-002 sample", (0.1, 20.0), 60), ("seed-001 actuator", (0.1, 9.0), 60),
               ("seed-000 sensor", (10.0, 100.0), 60)]


def per_temperature_section(quick: bool):
    print("\n## 2. Per-temperature fits at equal order (4 zeros / 4 poles), every temperature of the protocol\n")
    have_vf = importlib.util.find_spec("skrf") is not None
    if not have_vf:
        print("(scikit-rf not installed: VectorFitting column skipped)\n")
    print("Relative RMS error against the noisy data (mean / worst over temperatures), against the "
          "noise-free response in brackets; 'stable' = all poles in the open left half plane at every "
          f"temperature; time per temperature. Noise {NOISE.sigma_db} dB / {NOISE.sigma_deg}° "
          f"(floor ≈ {_noise_floor(NOISE):.3f}).\n")
    print("| data | method | error vs data mean / worst | (vs truth mean / worst) | stable at all T | time per T [ms] |")
    print("|:--|:--|--:|--:|:--:|--:|")
    m = n = 4
    for sample, band, nf in PER_T_CASES:
        temps = TEMPS.get(sample, SEED001_TEMPS)
        data, truth = generate_sweep(sample, temps, np.geomspace(band[0], band[1], nf), seed=11)
        methods = {"ours (RationalFit)": [], "scipy AAA": [], "Levy (invfreqs)": []}
        if have_vf:
            methods["scikit-rf VectorFitting"] = []
        RationalFit(m, n, raise_on_failure=False).fit_data(data.at_temperature(temps[0]))  # build solver once
        for temp in temps:
            d = data.at_temperature(temp)
            fk, hk, w = d.frequency_hz, d.response, d.omega
            t0 = time.perf_counter()
            res = RationalFit(m, n, raise_on_failure=False).fit_data(d)
            dt = time.perf_counter() - t0
            methods["ours (RationalFit)"].append((res.model.frequency_response(fk), res.model.poles(), dt,
                                                         res.converged))
            t0 = time.perf_counter()
            hm, poles = _aaa(w, hk, n)
            methods["scipy AAA"].append((hm, poles, time.perf_counter() - t0, True))
            if have_vf:
                t0 = time.perf_counter()
                hm, poles = _vf(fk, hk, n)
                methods["scikit-rf VectorFitting"].append((hm, poles, time.perf_counter() - t0, True))
            t0 = time.perf_counter()
            hm, poles = _levy(w, hk, m, n)
            methods["Levy (invfreqs)"].append((hm, poles, time.perf_counter() - t0, True))
        for name, rows in methods.items():
            masks = [data.temperature_c == temp for temp in temps]
            e = [relative_rms_error(r[0], data.response[k]) for r, k in zip(rows, masks)]
            et = [relative_rms_error(r[0], truth[k]) for r, k in zip(rows, masks)]
            n_unstable = sum(not np.all(np.real(r[1]) < 0) for r in rows)
            conv = all(r[3] for r in rows)
            print(f"| {sample} {band[0]:g}–{band[1]:g} Hz | {name}{'' if conv else ' (NOT all converged)'} | "
                  f"{np.mean(e):.4f} / {np.max(e):.4f} | ({np.mean(et):.4f} / {np.max(et):.4f}) | "
                  f"{'yes' if n_unstable == 0 else f'NO ({n_unstable}/{len(rows)} T unstable)'} | "
                  f"{1e3 * np.mean([r[2] for r in rows]):.1f} |")


# --------------------------------------------------------------------------- 3. timing
def timing_section(quick: bool):
    print("\n## 3. Fit times: 10 temperatures x 60 frequencies, order 4/4, cubic schedules\n")
    print("seed-002 sample, 0.1–20 Hz, all ten seed-001 temperatures. 'first' is the first fit in "
          "the process (it builds any CasADi solver it needs), 'second' repeats it. Per-temperature fit times are in section 2.\n")
    data, _ = generate_sweep("seed-002 sample", SEED001_TEMPS, np.geomspace(0.1, 20.0, 60), seed=21)
    print("| method | form | run | total [s] | of which per-T stage [s] | of which joint NLP [s] | "
          "joint iterations | converged |")
    print("|:--|:--|:--|--:|--:|--:|--:|:--:|")
    for form in ("coefficients", "zpk"):
        for run in ("first", "second"):
            t0 = time.perf_counter()
            res = ScheduledFit(form, 4, 4, 3, raise_on_failure=False).fit_data(data)
            total = time.perf_counter() - t0
            joint = [e for e in res.history if e["stage"].startswith("joint")]
            per_t = [e for e in res.history if e["stage"].startswith("per-T")]
            print(f"| joint (ours) | {form} | {run} | {total:.2f} | {sum(e['time_s'] for e in per_t):.2f} | "
                  f"{sum(e['time_s'] for e in joint):.2f} | {sum(e['iterations'] for e in joint)} | "
                  f"{'yes' if res.converged else 'NO (' + res.status + ')'} |")
        for per_t_name in ("levy", "nlp"):
            t0 = time.perf_counter()
            res = ScheduledFit(form, 4, 4, 3, method="two-stage", per_temperature=per_t_name,
                               raise_on_failure=False).fit_data(data)
            total = time.perf_counter() - t0
            label = "two-stage, Levy first stage (papers')" if per_t_name == "levy" else "two-stage, NLP first stage"
            print(f"| {label} | {form} | cached | {total:.2f} | "
                  f"{sum(e['time_s'] for e in res.history if e['stage'].startswith('per-T')):.2f} | – | – | "
                  f"{'yes' if res.converged else 'NO (' + res.status + ')'} |")
    t0 = time.perf_counter()
    for temp in SEED001_TEMPS:
        d = data.at_temperature(temp)
        _levy(d.omega, d.response, 4, 4)
    print(f"| Levy alone, 10 temperatures (no schedule) | – | – | {time.perf_counter() - t0:.4f} | – | – | – | – |")


# --------------------------------------------------------------------------- 4. orders and claims
def _orders(sample, temps, f1, orders, seed):
    """Order selection on the noisy protocol sweep and on its noise-free truth."""
    data, truth = generate_sweep(sample, temps, f1, seed, noise=ORDER_NOISE)
    rep = order_selection(data.frequency_hz, data.temperature_c, data.response, orders,
                          data.magnitude_std_db, data.phase_std_deg)
    rep0 = order_selection(data.frequency_hz, data.temperature_c, truth, orders)
    print(rep.to_markdown())
    print("\nNoise-free truth (model bias only): " + "; ".join(
        f"{r.n_zeros}/{r.n_poles}: worst err {r.worst_relative_rms_error:.4f}, min fit {r.min_fit_percent:.2f} %"
        for r in rep0.rows))
    return rep, rep0


def _verdict(ok: bool) -> str:
    return "REPRODUCED" if ok else "NOT reproduced"


def order_section(quick: bool):
    claims = []
    print("\n## 4. Order selection and the papers' claims on physics sweeps\n")
    floor = _noise_floor(ORDER_NOISE)
    print(f"Protocol noise {ORDER_NOISE.sigma_db} dB / {ORDER_NOISE.sigma_deg}° (floor ≈ {floor:.3f}); "
          "'rel. RMS error' and 'fit %' (100·(1 − NRMSE), MATLAB ident) are against the noisy data; "
          "the noise-free line separates model bias from noise.\n")

    # ---- seed 001
    print("### Seed 001 protocol: 30 log-spaced lines on 0.1–9 Hz, 19 and 55 °C\n")
    f001 = np.geomspace(0.1, 9, 30)
    for sample in ("seed-001 actuator", "seed-001 actuator, r1'=2 Ω"):
        print(f"{sample}:\n")
        rep, rep0 = _orders(sample, [19.0, 55.0], f001, [(2, 2), (2, 3), (3, 3), (4, 4), (5, 5)], seed=31)
        e = {k: rep.row(k, k).worst_relative_rms_error for k in (2, 3, 4)}
        b = {k: rep0.row(k, k).worst_relative_rms_error for k in (2, 3, 4)}
        e23 = rep.row(2, 3).worst_relative_rms_error
        c1 = e[2] > 3 * e[3]
        c2 = e[4] > 0.8 * e[3]
        c2b = e23 >= 0.95 * e[3]
        print(f"\n- 2nd order clearly worse than 3rd: error ×{e[2] / e[3]:.1f} → {_verdict(c1)}")
        print(f"- 4th adds little over 3rd: error 4th/3rd = {e[4] / e[3]:.2f} (noise-free bias "
              f"{b[3]:.4f} → {b[4]:.4f}) → {_verdict(c2)}")
        print(f"- strictly proper 3rd order (2 zeros / 3 poles) fits no better than the proper 3/3: "
              f"error 2/3 ÷ 3/3 = {e23 / e[3]:.2f} → {_verdict(c2b)}\n")
        claims += [(f"001: 2nd order clearly worse ({sample})", c1), (f"001: 4th adds little over 3rd ({sample})", c2),
                   (f"001: strictly proper 3rd no better than proper ({sample})", c2b)]

    # zeros / poles of per-temperature fits at all ten temperatures (seed 001's observations)
    data, truth = generate_sweep("seed-001 actuator", SEED001_TEMPS, f001, seed=32, noise=ORDER_NOISE)
    rhp_pair, big_pole = [], []
    for temp in SEED001_TEMPS:
        d = data.at_temperature(temp)
        z = RationalFit(3, 3, raise_on_failure=False).fit_data(d).model.zeros()
        rhp_pair.append(bool(np.sum((z.real > 0) & (np.abs(z.imag) > 1e-9)) == 2))
        p = RationalFit(4, 4, raise_on_failure=False).fit_data(d).model.poles()
        big_pole.append(float(np.max(np.abs(p)) / (2 * np.pi * 9.0)))
    c3 = all(rhp_pair)
    c4 = sum(r > 10 for r in big_pole) >= len(big_pole) / 2
    print("Seed-001 actuator, all ten temperatures (noisy protocol):")
    print(f"- 3/3 fit has a complex pair of right-half-plane zeros at every temperature: "
          f"{sum(rhp_pair)}/{len(rhp_pair)} temperatures → {_verdict(c3)}")
    print(f"- 4/4 fit 'often shows one very large negative pole' (|p| > 10 × band edge): "
          f"{sum(r > 10 for r in big_pole)}/{len(big_pole)} temperatures (largest |p| / (2π·9 Hz) from "
          f"{min(big_pole):.1f} to {max(big_pole):.1f}) → {_verdict(c4)}")
    # response shape: resonance shift and the 19 vs 55 °C magnitude difference (noise-free, dense)
    fd = np.geomspace(0.1, 9, 400)
    sw = synthesize_sweep(physics_model("seed-001 actuator"), "M", fd, [19.0, 55.0], None)
    _, _, H = sw.grid()
    fpk = fd[np.argmax(np.abs(H), axis=1)]
    diff = 20 * np.log10(np.abs(H[0]) / np.abs(H[1]))   # > 0: 19 °C larger
    i = int(np.argmax(np.abs(diff)))
    j = int(np.argmax(diff))
    k3 = int(np.argmin(np.abs(fd - 3.0)))
    c5 = fpk[1] < fpk[0]
    c6 = diff[i] > 3.5 and 1.5 < fd[i] < 6
    print(f"- resonance shifts lower as T rises: peak {fpk[0]:.2f} Hz at 19 °C → {fpk[1]:.2f} Hz at 55 °C → {_verdict(c5)}")
    print(f"- largest 19 vs 55 °C magnitude difference ≈ 7 dB near 3 Hz, 19 °C larger: the physics' largest "
          f"difference is {diff[i]:+.2f} dB at {fd[i]:.2f} Hz ({'19' if diff[i] > 0 else '55'} °C larger); "
          f"19 °C is larger by at most {diff[j]:.2f} dB (at {fd[j]:.2f} Hz), {diff[k3]:+.2f} dB at 3 Hz "
          f"→ {_verdict(c6)}\n")
    claims += [("001: complex RHP zero pair at every T (3/3)", c3), ("001: 4th order shows a very large pole", c4),
               ("001: resonance shifts lower with T", c5), ("001: ~7 dB drop near 3 Hz from 19 to 55 °C", c6)]

    # ---- seed 002
    print("### Seed 002 protocol: seed-002 sample (Table 3), 60 log-spaced lines on 0.1–100 Hz, 300 K, "
          "the four printed widths\n")
    c7 = c8 = True
    for k, width_mm in enumerate((4.0, 2.0, 1.0, 0.5)):
        data, truth = generate_sweep("seed-002 sample", [26.85], np.geomspace(0.1, 100, 60), seed=41,
                                     noise=ORDER_NOISE, overrides={"W": width_mm * 1e-3})
        rep = order_selection(data, orders=[(1, 4), (2, 5)])
        rep0 = order_selection(data.frequency_hz, data.temperature_c, truth, orders=[(1, 4), (2, 5)])
        if k == 0:
            print(rep.to_markdown() + "\n")
        f14, f25 = rep.row(1, 4).min_fit_percent, rep.row(2, 5).min_fit_percent
        g14, g25 = rep0.row(1, 4).min_fit_percent, rep0.row(2, 5).min_fit_percent
        c7 &= f25 >= 92.5
        c8 &= f14 < f25 - 2
        print(f"- W = {width_mm:g} mm: fit 4p/1z {f14:.2f} %, 5p/2z {f25:.2f} % (noise-free {g14:.2f} % / {g25:.2f} %)")
    print(f"\n- 5 poles / 2 zeros fit ≥ 92.5 % at every width → {_verdict(c7)} (the noisy fit % is set by the "
          f"protocol noise: the noise-free 5p/2z fit is ≈ 100 %)")
    print(f"- 4 poles / 1 zero fits the resonance but misses the response (fit % more than 2 points below "
          f"5p/2z) → {_verdict(c8)}: the physics itself is fitted by 4p/1z nearly as well as by 5p/2z; the "
          f"paper's misfit is of measured data, not of this model\n")
    claims += [("002: 5p/2z fit ≥ 92.5 %", c7), ("002: 4p/1z clearly worse than 5p/2z", c8)]

    # ---- seed 000
    print("### Seed 000 protocol: seed-000 sensor, 60 log-spaced lines on 10–100 Hz, 23 and 65 °C\n")
    rep, rep0 = _orders("seed-000 sensor", [23.0, 65.0], np.geomspace(10, 100, 60),
                        [(1, 1), (2, 2), (3, 3), (4, 4)], seed=51)
    b = {k: rep0.row(k, k).worst_relative_rms_error for k in (1, 2, 3, 4)}
    need4 = b[3] > 2 * b[4] and rep.row(3, 3).worst_relative_rms_error > 1.2 * rep.row(4, 4).worst_relative_rms_error
    print(f"\n- does the physics need seed 000's 4/4? noise-free bias 2/2 {b[2]:.2e}, 3/3 {b[3]:.2e}, "
          f"4/4 {b[4]:.2e} → {'yes' if need4 else 'no: a lower order already reaches the noise floor'}")
    fd = np.geomspace(10, 100, 200)
    sw = synthesize_sweep(physics_model("seed-000 sensor"), "S", fd, SEED000_TEMPS, None)
    _, temps, H = sw.grid()
    mag, ph = 20 * np.log10(np.abs(H)), np.degrees(np.unwrap(np.angle(H), axis=1))
    slope = (mag[:, -1] - mag[:, 0]) / 20.0   # dB per decade / 20 = log-log slope
    c9 = bool(np.all(np.diff(mag[:, -1]) < 0))
    c10 = bool(np.all(np.diff(ph[:, 0]) < 0))
    print(f"- high-frequency gain decreases with T: |S(100 Hz)| {mag[0, -1]:.2f} dB at 23 °C → "
          f"{mag[-1, -1]:.2f} dB at 65 °C, monotone → {_verdict(c9)}")
    print(f"- phase lag increases with T: phase at 10 Hz {ph[0, 0]:+.1f}° → {ph[-1, 0]:+.1f}°, monotone → {_verdict(c10)}")
    num = [-17.3, 2.2e4, -1.0e7, -9.4e8, 4.5e10]
    den = [1.0, 835.0, 6.3e5, 2.5e8, 4.4e10]
    s = 2j * np.pi * np.array([10.0, 100.0])
    hp = np.polyval(num, s) / np.polyval(den, s)
    k35 = list(temps).index(35.0)
    print(f"- cutoff frequency decreases with T (high-pass view): not testable — the physics magnitude rises "
          f"with log-log slope {slope.min():.2f}–{slope.max():.2f} over the whole band (differentiator regime, "
          f"corner above 100 Hz); seed 000's printed 35 °C model goes {20 * np.log10(abs(hp[0])):.1f} → "
          f"{20 * np.log10(abs(hp[1])):.1f} dB and {np.degrees(np.angle(hp[0])):+.0f}° at 10 Hz, the physics "
          f"{mag[k35, 0]:.1f} → {mag[k35, -1]:.1f} dB and {ph[k35, 0]:+.0f}°")
    claims += [("000: HF gain decreases with T", c9), ("000: phase lag increases with T", c10),
               ("000: physics needs 4/4", need4)]

    print("\n### Summary of the claims checked on the physics sweeps\n")
    print("| claim | on physmodel sweeps |")
    print("|:--|:--|")
    for text, ok in claims:
        print(f"| {text} | {_verdict(ok) if not text.startswith('000: physics needs') else ('yes' if ok else 'no')} |")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="fewer noise seeds in section 1")
    p.add_argument("--sections", default="1234", help="which sections to run, e.g. '14' (default: all)")
    args = p.parse_args(argv)
    t0 = time.perf_counter()
    print("# surrogate benchmark (data: physmodel sweeps, see generate_sweep)")
    sections = {"1": held_out_section, "2": per_temperature_section, "3": timing_section, "4": order_section}
    for key, run in sections.items():
        if key in args.sections:
            run(args.quick)
    print(f"\n(total {time.perf_counter() - t0:.1f} s)")


if __name__ == "__main__":
    main()
