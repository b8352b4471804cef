"""The steps a scenario can run (``[sweep]``, ``[surrogate]``, ``[inversion]`` ...), each a function
of the run context (:class:`scenarios.context.RunContext`) that adds data files, figures, metrics and a
report section; :data:`STEPS` maps a scenario table to its step.  A new step is a function here
(or in a module of its own, like :mod:`scenarios.steps_control`), its table in
:data:`scenarios.spec.SECTIONS` and its place in :data:`scenarios.spec.STEP_ORDER`.
"""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import numpy as np

from .context import RunContext, md_table
from .spec import ScenarioError
from .steps_chain import step_chain
from .steps_control import step_control_route
from .steps_next_measurement import step_next_measurement


def _slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "_", text.lower()).strip("_")


def _grid(cfg: dict, fmin: float, fmax: float, points: int) -> np.ndarray:
    lo, hi, n = cfg.get("fmin_hz", fmin), cfg.get("fmax_hz", fmax), cfg.get("points", points)
    if not (0 < lo < hi) or n < 2:
        raise ScenarioError(f"need 0 < fmin_hz < fmax_hz and points >= 2, got {lo}, {hi}, {n}")
    return np.geomspace(lo, hi, n)


# ---------------------------------------------------------------------------- steps
def build_model(ctx: RunContext):
    """The ``[model]`` table: the parameter set (with its overrides) and the physics model, into ``ctx``."""
    from physmodel import get_parameter_set, physics_model

    m = ctx.spec.section("model")
    p = get_parameter_set(m["set"], **m.get("params", {}))
    ctx.base_params = p
    if m["kind"] == "actuator" and "kernel" in m:
        raise ScenarioError(f"{ctx.spec.path}: [model] kernel applies to sensors only")
    ctx.model = physics_model(m["kind"], p, kernel=m.get("kernel", "boundary_charge"))


def _quantity(ctx) -> str:
    m = ctx.spec.section("model")
    return m.get("quantity", "M" if m["kind"] == "actuator" else "S")


def _noise(ctx):
    from physmodel.data.sweep import ComplexGaussianNoise, MagnitudePhaseNoise

    n = ctx.spec.section("noise")
    kind = n.get("kind", "none")
    if kind == "magphase":
        return MagnitudePhaseNoise(n.get("sigma_db", 0.1), n.get("sigma_deg", 1.0)), n.get("seed")
    if kind == "complex":
        return ComplexGaussianNoise(n.get("sigma", 0.01)), n.get("seed")
    return None, None


def _subset(sw, temps):
    """The lines of ``sw`` at ``temps`` (all of it when none match)."""
    drop = [t for t in sw.temperatures() if t not in temps]
    return sw if len(drop) == sw.temperatures().size else (sw.exclude(drop) if drop else sw)


def _resonance_hz(f, h) -> float:
    """Frequency of the highest interior local maximum of |h| (NaN when there is none)."""
    a = np.abs(h)
    k = np.flatnonzero((a[1:-1] > a[:-2]) & (a[1:-1] >= a[2:])) + 1
    return float(f[k[np.argmax(a[k])]]) if k.size else float("nan")


def step_sweep(ctx: RunContext):
    from physmodel.data.sweep import synthesize_sweep

    from . import plots

    cfg = ctx.spec.section("sweep")
    temps = cfg["temperatures_c"]
    q = _quantity(ctx)
    if cfg.get("source", "synthetic") == "virtual_lab":
        # the experiment itself: excitation -> physics time records with noise and quantisation -> FRF
        from .virtual_lab import from_config

        lab = from_config(ctx.model, cfg, ctx.spec.section("noise"), where=f"{ctx.spec.path}: ")
        ctx.data = lab.sweep
        f = np.unique(ctx.data.frequency_hz)
        ctx.exact = synthesize_sweep(ctx.model, q, f, temps)
        ctx.metric("sweep.lab_duration_s", lab.duration_s)
        ctx.metric("sweep.median_std_db", float(np.median(ctx.data.magnitude_std_db)))
    else:
        if ctx.spec.section("noise").get("kind") == "time":
            raise ScenarioError(f"{ctx.spec.path}: [noise] kind = \"time\" needs [sweep] source = \"virtual_lab\"")
        f = _grid(cfg, 0.1, 100.0, 40)
        noise, seed = _noise(ctx)
        ctx.exact = synthesize_sweep(ctx.model, q, f, temps)
        ctx.data = synthesize_sweep(ctx.model, q, f, temps, noise, seed) if noise else ctx.exact
    ctx.file(ctx.data.to_csv(ctx.out / "data" / "sweep.csv"))
    ctx.file(ctx.data.to_npz(ctx.out / "data" / "sweep.npz"))
    ctx.file(ctx.exact.to_csv(ctx.out / "data" / "sweep_exact.csv"))
    shown = cfg.get("plot_temperatures_c", temps)
    ctx.file(plots.bode([_subset(ctx.data, shown), _subset(ctx.exact, shown)], ctx.out / "bode.png",
                        labels=["data", "physics"], styles=["o", "-"],
                        title=f"{ctx.base_params.name}: {ctx.exact.metadata['description']}"))
    f0, T, H = ctx.exact.grid()
    cold, hot = np.abs(H[0]), np.abs(H[-1])
    ddb = 20 * np.log10(cold / hot)
    k = int(np.argmax(np.abs(ddb)))
    fd = np.geomspace(f0[0], f0[-1], 4000)             # resonance from the physics on a dense grid
    Hd = ctx.model.frequency_response(fd, [T[0], T[-1]], quantities=(q,))[q][0]
    pk = [_resonance_hz(fd, h) for h in Hd]
    ctx.metric("sweep.lines", ctx.data.frequency_hz.size)
    ctx.metric("sweep.max_db_difference", abs(ddb[k]))
    ctx.metric("sweep.max_db_difference_frequency_hz", f0[k])
    ctx.metric("sweep.cold_minus_hot_db_at_max", ddb[k])
    ctx.metric("sweep.gain_ratio_hot_cold_at_fmax", hot[-1] / cold[-1])
    ctx.metric("sweep.peak_frequency_shift_hz", pk[1] - pk[0])
    ctx.metric("sweep.peak_frequency_hz", pk[0])
    ctx.section("Frequency sweeps",
                f"{len(temps)} temperatures × {f.size} log-spaced lines, {f[0]:g}–{f[-1]:g} Hz, "
                f"{ctx.data.output_unit}/{ctx.data.input_unit}; noise: {ctx.data.metadata.get('noise', 'none')}"
                f" (seed {ctx.data.metadata.get('seed', '-')}).", "", "![Bode](bode.png)", "",
                f"Largest magnitude difference between {T[0]:g} °C and {T[-1]:g} °C: {ddb[k]:+.2f} dB at "
                f"{f0[k]:.3g} Hz (cold minus hot); resonance peak moves from {pk[0]:.3g} Hz to {pk[1]:.3g} Hz."
                if T.size > 1 else f"Resonance peak at {pk[0]:.3g} Hz.")


def step_surrogate(ctx: RunContext):
    from surrogate import fit_sweep, relative_rms_error

    from . import plots

    cfg = ctx.spec.section("surrogate")
    held = ctx.spec.section("sweep").get("held_out_c", [])
    missing = [t for t in held if t not in ctx.data.temperatures()]
    if missing:
        raise ScenarioError(f"{ctx.spec.path}: [sweep] held_out_c {missing} are not in temperatures_c")
    train = ctx.data.exclude(held) if held else ctx.data
    nz, npo = cfg.get("n_zeros", 3), cfg.get("n_poles", 3)
    kw = {k: cfg[k] for k in ("method", "weighting") if k in cfg}
    try:
        fit = fit_sweep(train, nz, npo, cfg.get("degree", 2), form=cfg.get("form", "zpk"), raise_on_failure=False, **kw)
    except ValueError as exc:        # the surrogate package refuses an order/degree the data cannot carry
        raise ScenarioError(f"{ctx.spec.path}: [surrogate] n_zeros={nz}, n_poles={npo}, degree={cfg.get('degree', 2)}: "
                            f"{exc}") from None
    ctx.fit = fit
    model = fit.model
    model.to_json(ctx.out / "surrogate.json")
    ctx.file(ctx.out / "surrogate.json")
    ctx.metric("surrogate.converged", fit.converged)
    rows, train_err, held_err = [], [], []
    for t in ctx.exact.temperatures():
        ex = ctx.exact.select(t)
        g = model.frequency_response(ex.frequency_hz, t, extrapolate=True)
        e = relative_rms_error(g, ex.response)
        (held_err if t in held else train_err).append(e)
        rows.append((f"{t:g}", "held out" if t in held else "fit", f"{e:.4f}"))
    ctx.metric("surrogate.train_rel_rms_max", max(train_err))
    if held_err:
        ctx.metric("surrogate.heldout_rel_rms_max", max(held_err))
    lo, hi = model.temperature_range_c if model.is_scheduled else (ctx.exact.temperatures()[0],) * 2
    grid = np.linspace(lo, hi, 41)
    n_rhp = [int(np.sum(model.zeros(t).real > 0)) for t in grid]
    ctx.metric("surrogate.rhp_zeros_min", min(n_rhp))
    ctx.metric("surrogate.rhp_zeros_max", max(n_rhp))
    stab = model.stability_check(201)
    ctx.metric("surrogate.stable", stab.stable)
    ctx.metric("surrogate.max_pole_real_rad_s", stab.max_pole_real_part_rad_s)
    resp = model.frequency_response(ctx.data.frequency_hz, ctx.data.temperature_c, extrapolate=True)
    sur = replace(ctx.data, response=resp, magnitude_std_db=None, phase_std_deg=None)
    shown = ctx.spec.section("sweep").get("plot_temperatures_c", list(ctx.data.temperatures()))
    ctx.file(plots.bode([_subset(ctx.data, shown), _subset(sur, shown)], ctx.out / "surrogate_bode.png",
                        labels=["data", "surrogate"], styles=["o", "-"],
                        title=f"{cfg.get('form', 'zpk')} {nz}/{npo} surrogate, degree {cfg.get('degree', 2)} in T"))
    ctx.file(plots.pole_zero_locus(model, grid, ctx.out / "pole_zero_locus.png",
                                   title=f"surrogate poles (x) and zeros (o), {lo:g}–{hi:g} °C"))
    ctx.section("Temperature-scheduled surrogate",
                f"{cfg.get('form', 'zpk')} form, {nz} zeros / {npo} poles, degree {cfg.get('degree', 2)} in T, "
                f"{fit.method} fit on {train.temperatures().size} temperatures "
                f"({'converged' if fit.converged else 'NOT CONVERGED: ' + str(fit.status)}); model in `surrogate.json`.",
                "", "![surrogate Bode](surrogate_bode.png)", "", "![pole/zero locus](pole_zero_locus.png)", "",
                "Relative RMS error sqrt(mean |G/P − 1|²) against the noise-free physics P:", "",
                md_table(["T [°C]", "role", "rel. RMS error"], rows), "",
                f"Right-half-plane zeros over {lo:g}–{hi:g} °C: {min(n_rhp)}–{max(n_rhp)}; "
                f"largest pole real part {stab.max_pole_real_part_rad_s:.3g} rad/s.")


def _plant_response(ctx: RunContext, f_hz: float, T: float) -> complex:
    """The physics response at one line in the sweep's display units (mm/V or uA/mm)."""
    from physmodel.data.sweep import synthesize_sweep

    return complex(synthesize_sweep(ctx.model, _quantity(ctx), [f_hz], [T]).response[0])


def _stimulus(exp: dict, t: np.ndarray, lead: float = 0.0, ramp: float = 0.0) -> np.ndarray:
    """Sum of sines sharing ``amplitude_mm`` equally, zero for ``lead`` s, then faded in with a
    raised cosine over ``ramp`` s (so the noncausal inverse can pre-actuate inside the record)."""
    freqs = exp.get("frequencies_hz", [1.0])
    a = exp["amplitude_mm"] / len(freqs)
    tau = t - lead
    env = np.where(tau < 0, 0.0, np.where(tau < ramp, 0.5 * (1 - np.cos(np.pi * tau / max(ramp, 1e-300))), 1.0))
    return env * sum(a * np.sin(2 * np.pi * fr * tau) for fr in freqs)


def step_inversion(ctx: RunContext):
    from inversion import Limits, decode_sensor, feedforward
    from physmodel.data.timesim import free_release, simulate, time_grid

    from . import plots

    cfg = ctx.spec.section("inversion")
    fs, dur = cfg.get("fs_hz", 1000.0), cfg.get("duration_s", 8.0)
    settle, margin = cfg.get("settle_s", dur / 3), cfg.get("end_margin_s", 0.5)
    lead, ramp = cfg.get("lead_s", 0.0), cfg.get("ramp_s", 0.0)
    preview = cfg.get("preview", "inf")
    if isinstance(preview, str) and preview not in ("inf", "auto", "4/r0"):
        raise ScenarioError(f"{ctx.spec.path}: [inversion] preview must be 'inf', 'auto', '4/r0' or seconds, "
                            f"got {preview!r}")
    if not settle < dur - margin:
        raise ScenarioError(f"{ctx.spec.path}: [inversion] settle_s={settle} leaves no error window in {dur} s")
    is_act = ctx.spec.section("model")["kind"] == "actuator"
    if is_act != (_quantity(ctx) == "M") or (not is_act and _quantity(ctx) != "S"):
        raise ScenarioError(f"{ctx.spec.path}: [inversion] needs quantity M (actuator) or S (sensor)")
    # the drive limit: inversion's default (3 V) unless the scenario states one, or "off" for a
    # virtual plant that takes any voltage
    mv = cfg.get("max_voltage_v")
    limits = "default" if mv is None else "off" if mv == "off" else Limits(max_voltage=float(mv))
    t = time_grid(dur, fs)
    rows, peaks = [], []
    for exp in cfg["experiments"]:
        T = exp["temperature_c"]
        Tm = exp.get("model_temperature_c", T)
        G = ctx.fit.model.at(Tm, extrapolate=True)
        stim = exp.get("stimulus", "sine")
        if is_act:
            if stim != "sine":
                raise ScenarioError(f"{ctx.spec.path}: experiment {exp['name']!r}: actuators track sines only")
            ref = _stimulus(exp, t, lead, ramp)                               # mm
            ff = feedforward(G, t, ref, preview=preview, limits=limits)
            u = ff.output                                                     # V
            peaks.append(ctx.metric(f"inversion.{_slug(exp['name'])}.peak_voltage_v", ff.limit_report.peak))
            got = simulate(ctx.model, T, t, u).output * 1e3                    # m -> mm
            labels = ("reference", "tip displacement (physics plant)")
        else:
            if stim == "release":
                ts = free_release(ctx.model, T, exp["amplitude_mm"] * 1e-3, exp.get("t_release_s", dur / 2), dur, fs)
                ref, cur = ts.input * 1e3, ts.output * 1e6                    # mm, uA
            else:
                ref = _stimulus(exp, t, lead, ramp)
                cur = simulate(ctx.model, T, t, ref * 1e-3).output * 1e6
            if exp.get("noise_rms", 0.0) > 0:
                if "seed" not in exp:
                    raise ScenarioError(f"experiment {exp['name']!r}: noise_rms needs a seed")
                cur = cur + exp["noise_rms"] * np.random.default_rng(exp["seed"]).standard_normal(t.size)
            got = decode_sensor(G, t, cur, preview=preview).output          # mm
            labels = ("tip displacement", "decoded from current")
        w_lo, w_hi = exp.get("window_s", [settle, t[-1] - margin])
        win = (t >= w_lo) & (t <= w_hi)
        if not win.any():
            raise ScenarioError(f"experiment {exp['name']!r}: error window {w_lo}-{w_hi} s holds no sample")
        if "highpass_hz" in exp:
            from scipy.signal import butter, sosfiltfilt

            sos = butter(2, exp["highpass_hz"], "highpass", fs=fs, output="sos")
            ref, got = sosfiltfilt(sos, ref), sosfiltfilt(sos, got)
        err = got - ref
        key = f"inversion.{_slug(exp['name'])}"
        emax = ctx.metric(f"{key}.error_max_mm", np.max(np.abs(err[win])))
        ctx.metric(f"{key}.error_rel", emax / exp["amplitude_mm"])
        ctx.metric(f"{key}.error_rms_mm", np.sqrt(np.mean(err[win] ** 2)))
        freqs = exp.get("frequencies_hz", [])
        if stim == "sine" and len(freqs) == 1 and "highpass_hz" not in exp:
            # steady-state oracle from the physics frequency response: |error| = A |P(jω)/G(jω) − 1|
            P = _plant_response(ctx, freqs[0], T)
            g = complex(G(2j * np.pi * freqs[0]))
            ctx.metric(f"{key}.predicted_error_mm", exp["amplitude_mm"] * abs(P / g - 1))
            if is_act:
                # the prediction is the model's error alone; what the inversion adds itself (the
                # preview's truncation error and its sampling bound, through |P|) must be small beside
                # it for the prediction to hold: said, so a scenario can check that premise
                ctx.metric(f"{key}.inversion_error_bound_mm",
                           abs(P) * (ff.truncation_error + ff.discretisation_error_estimate))
        png = f"inversion_{_slug(exp['name'])}.png"
        if "highpass_hz" in exp:
            labels = tuple(f"{lab}, high-passed at {exp['highpass_hz']:g} Hz" for lab in labels)
        ctx.file(plots.tracking(t, ref, got, ctx.out / png, labels=labels, window=(w_lo, w_hi),
                                title=f"{exp['name']}: physics at {T:g} °C, surrogate at {Tm:g} °C"))
        rows.append((exp["name"], f"{T:g}", f"{Tm:g}", f"{emax:.4f}", f"{emax / exp['amplitude_mm']:.3f}", f"![]({png})"))
    what = "feedforward (desired tip displacement → voltage) applied to the physics plant" if is_act else \
        "sensor decoding (short-circuit current → tip displacement) of the physics sensor's output"
    drive = ""
    if is_act:
        from inversion.limits import DEFAULT_MAX_VOLTAGE

        top = max(peaks)
        drive = (f" Drive limit: {'off (a virtual plant takes any voltage)' if mv == 'off' else f'{mv:g} V' if mv is not None else f'{DEFAULT_MAX_VOLTAGE:g} V (the default)'}; "
                 f"peak drive {top:.3g} V" + (f" — **above the {DEFAULT_MAX_VOLTAGE:g} V a strip takes: not for a real strip**"
                                               if top > DEFAULT_MAX_VOLTAGE else "") + ".")
    ctx.section("Stable inversion", f"{what}; preview {preview}; {fs:g} Hz, {dur:g} s records; error bound = "
                f"max |error| over {settle:g}–{t[-1] - margin:g} s unless the experiment sets its own window (shaded)."
                + drive, "",
                md_table(["experiment", "plant T [°C]", "model T [°C]", "max |error| [mm]", "relative", "traces"], rows))


def step_widths(ctx: RunContext):
    from physmodel import ActuatorModel

    from . import plots

    cfg = ctx.spec.section("widths")
    f = _grid(cfg, 0.5, 50.0, 150)
    T = cfg.get("temperature_c", 26.85)
    widths = cfg.get("widths_m", [4e-3, 2e-3, 1e-3, 0.5e-3])
    M = ActuatorModel([ctx.base_params.replace(W=w) for w in widths]).frequency_response(f, [T])["M"][:, 0]
    dev = float(np.max(np.abs(M / M[0] - 1)))
    ctx.metric("widths.max_rel_change", dev)
    ctx.file(plots.curves(f, {f"W = {w * 1e3:g} mm": 20 * np.log10(np.abs(m) * 1e3) for w, m in zip(widths, M)},
                          ctx.out / "widths.png", "frequency [Hz]", "magnitude [dB mm/V]", f"width study at {T:g} °C"))
    ctx.section("Width study", f"Physics model at widths {[w * 1e3 for w in widths]} mm, {T:g} °C: largest relative "
                f"change of M(jω) {dev:.1e} (the model is width-independent; measured strips are not).", "",
                "![widths](widths.png)")


def step_taylor(ctx: RunContext):
    from physmodel import ActuatorModel
    from physmodel.reduced import reduced_frequency_response

    from . import plots

    cfg = ctx.spec.section("taylor")
    f = _grid(cfg, 0.5, 50.0, 150)
    T = cfg.get("temperature_c", 26.85)
    lo, hi = cfg.get("band_hz", [2.0, 30.0])
    act = ActuatorModel(ctx.base_params)
    ex = act.frequency_response(f, [T])["M"][0, 0]
    st = act.state([T])
    band = (f >= lo) & (f <= hi)
    curves, rows = {"infinite-dimensional": 20 * np.log10(np.abs(ex) * 1e3)}, []
    for k in cfg.get("orders", [1, 2, 3, 4]):
        red = reduced_frequency_response(st, f, k)
        curves[f"Taylor order {k}"] = 20 * np.log10(np.abs(red) * 1e3)
        e = ctx.metric(f"taylor.order_{k}_max_db_error", np.max(np.abs(20 * np.log10(np.abs(red / ex)))[band]))
        rows.append((k, f"{e:.3f}"))
    ctx.file(plots.curves(f, curves, ctx.out / "taylor_orders.png", "frequency [Hz]", "magnitude [dB mm/V]",
                          f"reduced (Taylor) models around the first mode, {T:g} °C"))
    ctx.section("Reduced (Taylor) models", "![Taylor orders](taylor_orders.png)", "",
                md_table(["Taylor order", f"max |error| {lo:g}–{hi:g} Hz [dB]"], rows))


def step_blackbox(ctx: RunContext):
    from surrogate import RationalFit, fit_percent

    from . import plots

    cfg = ctx.spec.section("blackbox")
    T = cfg.get("temperature_c", float(ctx.data.temperatures()[0]))
    sw = ctx.data.select(T)
    curves, rows = {"data": sw.magnitude_db}, []
    for nz, npo in cfg["orders"]:
        try:
            r = RationalFit(nz, npo, raise_on_failure=False).fit(sw.frequency_hz, sw.temperature_c, sw.response)
        except ValueError as exc:
            raise ScenarioError(f"{ctx.spec.path}: [blackbox] orders [{nz}, {npo}]: {exc}") from None
        g = r.model.frequency_response(sw.frequency_hz)
        fp = ctx.metric(f"blackbox.z{nz}_p{npo}.fit_percent", fit_percent(g, sw.response))
        ctx.metric(f"blackbox.z{nz}_p{npo}.converged", r.converged)
        curves[f"{nz} zeros / {npo} poles"] = 20 * np.log10(np.abs(g))
        rows.append((nz, npo, f"{fp:.2f}", "yes" if r.converged else "NO"))
    ctx.file(plots.curves(sw.frequency_hz, curves, ctx.out / "blackbox.png", "frequency [Hz]",
                          f"magnitude [dB {sw.output_unit}/{sw.input_unit}]", f"black-box fits at {T:g} °C"))
    ctx.section("Black-box orders", "fit = 100 (1 − NRMSE) on the sweep at "
                f"{T:g} °C.", "", md_table(["zeros", "poles", "fit [%]", "converged"], rows), "",
                "![black-box fits](blackbox.png)")


def step_discrepancy(ctx: RunContext):
    from physmodel.data.sweep import synthesize_sweep
    from physmodel.effects import EffectModel
    from physmodel.estimation.discrepancy import diagnose

    from . import plots

    cfg = ctx.spec.section("discrepancy")
    kind, q = ctx.spec.section("model")["kind"], _quantity(ctx)
    effects = cfg.get("effects", {})
    if not effects:
        raise ScenarioError(f"{ctx.spec.path}: [discrepancy] needs at least one hidden effect")
    kernel = ctx.spec.section("model").get("kernel", "boundary_charge")
    truth = EffectModel(ctx.base_params, kind, effects, kernel=kernel)
    noise, seed = _noise(ctx)
    f = ctx.data.frequency_hz[ctx.data.temperature_c == ctx.data.temperatures()[0]]
    data = synthesize_sweep(truth, q, f, list(ctx.data.temperatures()), noise, seed)
    ctx.file(data.to_csv(ctx.out / "data" / "discrepancy_sweep.csv"))
    kw = {k: cfg[k] for k in ("null_draws", "null_refits", "alpha", "seed", "laws", "candidate_starts", "prior",
                              "baseline_starts") if k in cfg}
    for key in ("candidate_bounds", "plausible"):          # NAME = [LOWER, UPPER]
        if key in cfg:
            bad = [n for n, v in cfg[key].items() if len(v) != 2]
            if bad:
                raise ScenarioError(f"{ctx.spec.path}: [discrepancy] {key}.{bad[0]}: expected [LOWER, UPPER]")
            kw[key] = {n: (float(v[0]), float(v[1])) for n, v in cfg[key].items()}
    if "free" in cfg:
        kw["free"] = tuple(cfg["free"])
    if kind == "sensor":
        kw["kernel"] = kernel
    diag = diagnose(data, ctx.base_params, kind=kind, quantity=q, **kw)
    folder = diag.write_report(ctx.out / "discrepancy")
    plots.diagnosis_figures(diag, folder)
    for p in sorted(Path(folder).iterdir()):
        if not p.name.startswith("."):
            ctx.file(p)
    named = list(getattr(diag, "named", []) or [])
    hidden = sorted(effects)
    ctx.metric("discrepancy.hidden_effect_named", all(h in named for h in hidden))
    ctx.metric("discrepancy.n_named", len(named))
    from physmodel.estimation.discrepancy import gap_shrink

    ctx.metric("discrepancy.gap_shrink", gap_shrink(diag))
    fitted = diag.named_effect() or {}
    for eff, params in effects.items():                  # the known synthetic truth as oracle
        for par, true in params.items():
            got = fitted.get(eff, {}).get(par)
            if got is not None and true != 0:
                ctx.metric(f"discrepancy.{eff}.{par}.rel_error", abs(got["value"] / true - 1))
                lo, hi = got["ci95"]
                ctx.metric(f"discrepancy.{eff}.{par}.truth_in_ci95", lo <= true <= hi)
    ctx.section("Discrepancy demo", f"Hidden effect(s) in the synthetic data: {hidden} "
                f"({effects}); diagnosis against the plain `{ctx.base_params.name}` model: **{diag.verdict}**, "
                f"named {named}. {diag.message}", "",
                "Before (baseline model) and after (with the named effect fitted):", "",
                "![before](discrepancy/bode_before.png)", "", "![after](discrepancy/bode_after.png)", "",
                "Full diagnosis: `discrepancy/summary.md`, `discrepancy/report.json`.")


def step_fixtures(ctx: RunContext):
    from physmodel.data.files import read_sweep, write_sweep
    from physmodel.data.sweep import synthesize_sweep
    from physmodel.data.timesim import step

    cfg = ctx.spec.section("fixtures")
    formats = cfg.get("formats", ["csv", "npz", "mat"])
    bad = [f for f in formats if f not in ("csv", "npz", "mat")]
    if bad:
        raise ScenarioError(f"{ctx.spec.path}: [fixtures] formats {bad} unknown; expected csv, npz, mat")
    n = cfg.get("count", 3)
    f = _grid(cfg, 0.1, 50.0, 30)
    temps = cfg.get("temperatures_c", [25.0])
    q = _quantity(ctx)
    noise, _ = _noise(ctx)
    seeds = [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(cfg.get("seed", 0)).spawn(n)]
    is_act = ctx.spec.section("model")["kind"] == "actuator"
    manifest, worst = [], 0.0

    def make(i):
        return synthesize_sweep(ctx.model, q, f, temps, noise, seeds[i]) if noise else \
            synthesize_sweep(ctx.model, q, f, temps)

    for i in range(n):
        sw = make(i)
        sw.metadata["fixture"] = f"{ctx.spec.name} #{i}"
        for fmt in formats:
            p = write_sweep(sw, ctx.out / "fixtures" / f"sweep_{i:02d}.{fmt}")
            ctx.file(p)
            back = read_sweep(p)
            worst = max(worst, float(np.max(np.abs(back.response / sw.response - 1))))
            manifest.append({"file": p.name, "seed": seeds[i], "fingerprint": sw.fingerprint()})
        amp = 1.0 if is_act else 1e-3
        ts = step(ctx.model, temps[0], amp, cfg.get("step_duration_s", 1.0), cfg.get("fs_hz", 500.0),
                  output_noise_rms=cfg.get("noise_rms_mm", 0.005) * 1e-3 if is_act else 1e-9, seed=seeds[i])
        for fmt in [x for x in formats if x in ("csv", "npz")]:
            ctx.file(ts.save(ctx.out / "fixtures" / f"step_{i:02d}.{fmt}"))
    ctx.metric("fixtures.datasets", n)
    ctx.metric("fixtures.roundtrip_max_rel_error", worst)
    ctx.metric("fixtures.reproducible", make(0).fingerprint() == manifest[0]["fingerprint"])
    ctx.metric("fixtures.distinct", len({m["fingerprint"] for m in manifest}) == n if noise else 1.0)
    from physmodel.data.files import atomic_write

    ctx.file(atomic_write(ctx.out / "fixtures" / "manifest.json",
                          lambda fh: fh.write(json.dumps({"scenario": ctx.spec.name, "files": manifest}, indent=2))))
    ctx.section("Fixture batch", f"{n} seeded datasets (seeds from SeedSequence({cfg.get('seed', 0)}).spawn) in "
                f"{formats}: sweeps at {temps} °C, {f.size} lines, and a {'1 V' if is_act else '1 mm'} step record "
                f"each; read-back relative error {worst:.1e}; `fixtures/manifest.json` lists seeds and fingerprints.")


STEPS = {"sweep": step_sweep, "surrogate": step_surrogate, "control_route": step_control_route,
         "inversion": step_inversion, "widths": step_widths, "taylor": step_taylor, "blackbox": step_blackbox,
         "discrepancy": step_discrepancy, "next_measurement": step_next_measurement, "chain": step_chain,
         "fixtures": step_fixtures}
