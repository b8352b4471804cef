"""Temperature series of the ``[chain]`` step (issue 16): with the sensing chain fixed at its 35 °C
values, calibrate the polymer's temperature laws to what seed 000 prints about temperature.

What is printed per temperature (seed 000 Sec. II-B, III, IV-A; ``published.toml [sensor_seed000]``)
    * the full 4/4 model only at 35 °C (the ``[chain]`` step's data);
    * a0(T), the constant of the 4/4 model's monic denominator, as a cubic in T − 23.07 fitted to the
      invfreqs identifications at 23, 25, 30, 40, 50, 60, 65 °C (Fig. 7; the identified points are
      not printed, only the polynomial);
    * trends with rising T read off Fig. 5 (25, 45, 65 °C): cutoff and high-frequency gain fall, lag grows.

Data and noise model (stated, not tuned)
    a0(T_i) = the printed polynomial at the fit temperatures.  σ of ln a0 per temperature: the
    rounding of the printed polynomial coefficients (Monte Carlo, each uniform within half its last
    printed digit) in quadrature with the *identification* spread of a0: a0 of the equation-error
    4/4 fit (:func:`levy_4_4`, MATLAB ``invfreqs``' default, the seed's estimator) of the printed
    35 °C model perturbed with the 35 °C sweep's own per-line noise (rounding ⊕ 0.5 dB / 5°), i.e.
    how precisely a 10-100 Hz response measured that well fixes a0.  The trends carry a sign only,
    so they are checks, not residuals.

Model of the observation
    a0_model(T) = the denominator constant of the same equation-error 4/4 fit applied to physics +
    chain at T on the sweep's lines (chain elements at their 35 °C values; polymer parameters at
    35 °C from the chain fit; the laws move d, κe, E, Rp with T).  κe's default law (water
    permittivity, no free parameter) is replaced by a log-linear law started at the water
    permittivity's slope at 35 °C, so that ``laws.kappa_e.slope`` can be calibrated.  Variant
    ``beam_follows_E``: the tip-driven strip's mode is the strip's own (ω1 ∝ sqrt(E)), so its time
    constant follows E(T): τ(T) = τ(35 °C)·exp(−slope_E (T − 35)/2) (the rest of the chain fixed).

Calibration: the engine of ``calibrate`` (:func:`~physmodel.estimation.lsq.fit_parameters`) on a0(T)
as scalar observations (multi-start, 95 % Gauss-Newton intervals; undetermined = an interval wider than
the bounds, at a bound, or zero sensitivity, only the last held at its start value; χ² vs expectation)
and, on a misfit,
``calibrate``'s policy (Birge-widened intervals, no identifiability verdict).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .context import md_table

__all__ = ["A0Series", "LawCalibration", "a0_series", "calibrate_laws", "law_free_parameters", "levy_4_4",
           "printed_a0", "series_model", "trend_signs"]

#: The Fig. 5 temperatures of the printed trends [°C].
TRENDS_C = (25.0, 45.0, 65.0)
_EA, _SK, _SE = "laws.d.activation_energy", "laws.kappa_e.slope", "laws.E.slope"
#: Temperatures the printed a0(T) polynomial is drawn at. [°C]
_T_DENSE = np.linspace(20.0, 70.0, 101)


# ----------------------------------------------------------------------------- printed data
def _published():
    from physmodel.parameter_sets.published import load_published

    return load_published()["sensor_seed000"]


def printed_a0(temperature_c, coeffs=None) -> np.ndarray:
    """The printed a0(T) polynomial (seed 000 Sec. III) at ``temperature_c`` [°C]. [rad⁴/s⁴]"""
    p = _published()
    c = np.asarray(p["a0_poly_coeffs_times_1e10"] if coeffs is None else coeffs, float)
    x = np.atleast_1d(np.asarray(temperature_c, float)) - float(p["a0_poly_center_c"])
    return 1e10 * (c @ (x[:, None] ** np.arange(c.shape[-1])).T)


def _half_digit(c: float) -> float:
    """Half the last printed digit of ``c`` as written in published.toml (e.g. 8.56e-5 -> 5e-8)."""
    mant, _, exp = f"{abs(c):.6g}".partition("e")
    return 0.5 * 10.0 ** (int(exp or 0) - len(mant.partition(".")[2]))


def levy_4_4(frequency_hz, G) -> tuple[np.ndarray, np.ndarray]:
    """Equation-error (Levy) 4/4 fit, unit weights: min Σ|B(jω) − G(jω) A(jω)|², A monic.

    MATLAB ``invfreqs(h, w, 4, 4)`` without iterations (what seed 000 used).  ``G`` (..., F)
    complex; batched over leading axes.  Returns (num, den), each (..., 5), descending powers of
    s [rad/s].  Coefficients are solved in s/ω0 (ω0 the band's geometric centre) for conditioning;
    the minimiser does not depend on that scaling."""
    f = np.asarray(frequency_hz, float)
    G = np.asarray(G, complex)
    w0 = 2 * np.pi * math.sqrt(f[0] * f[-1])
    s = 2j * np.pi * f / w0
    P = s[:, None] ** np.arange(4, -1, -1)[None, :]                          # (F, 5): s⁴ … 1
    M = np.concatenate([np.broadcast_to(P, G.shape + (5,)), -G[..., None] * P[:, 1:]], axis=-1)   # (..., F, 9)
    y = G * P[:, 0]
    A = np.concatenate([M.real, M.imag], axis=-2)
    b = np.concatenate([y.real, y.imag], axis=-1)[..., None]
    Q, R = np.linalg.qr(A)
    x = np.linalg.solve(R, np.swapaxes(Q, -1, -2) @ b)[..., 0]
    scale = w0 ** np.arange(0, 5)[::-1]                                     # ω0⁴ … 1 for s⁴ … s⁰
    num = x[..., :5] * w0 ** 4 / scale
    den = np.concatenate([np.ones(x.shape[:-1] + (1,)), x[..., 5:]], axis=-1) * w0 ** 4 / scale
    return num, den


@dataclass(frozen=True)
class A0Series:
    """Printed a0(T) as data: ``temperatures_c`` [°C], ``a0`` [rad⁴/s⁴], ``sigma_ln`` [-] (σ of ln a0)
    with its parts ``rounding_ln`` and ``identification_ln`` [-]."""

    temperatures_c: np.ndarray
    a0: np.ndarray
    sigma_ln: np.ndarray
    rounding_ln: np.ndarray
    identification_ln: float
    source: str


def a0_series(sweep35, temperatures_c=None, draws: int = 2000, seed: int = 0) -> A0Series:
    """The printed a0(T) at the fit temperatures with the noise model of the module doc.

    ``sweep35``: the printed 35 °C model as a FrequencySweep with per-line σ (``printed_sweep``)."""
    p = _published()
    T = np.asarray(p["fit_temperatures_c"] if temperatures_c is None else temperatures_c, float)
    c = np.asarray(p["a0_poly_coeffs_times_1e10"], float)
    rng = np.random.default_rng(seed)
    half = np.array([_half_digit(x) for x in c])
    cd = c + rng.uniform(-1, 1, (draws, c.size)) * half
    rounding = np.log(printed_a0(T, cd) / printed_a0(T)).std(0)
    s_ln = sweep35.magnitude_std_db * math.log(10) / 20
    s_ph = np.radians(sweep35.phase_std_deg)
    noisy = sweep35.response * np.exp(rng.standard_normal((draws, s_ln.size)) * s_ln
                                      + 1j * rng.standard_normal((draws, s_ln.size)) * s_ph)
    a0n = levy_4_4(sweep35.frequency_hz, noisy)[1][:, -1]
    ident = float(np.std(np.log(np.abs(a0n))))
    return A0Series(T, printed_a0(T), np.hypot(rounding, ident), rounding, ident,
                    "seed 000 Sec. III a0(T) polynomial at its fit temperatures; σ: coefficient rounding ⊕ "
                    f"invfreqs-default identification spread under the 35 °C sweep's noise ({draws} draws)")


def trend_signs(frequency_hz, G) -> dict:
    """Per temperature (rows of ``G``, ascending T): cutoff [Hz] (lowest line where |G| reaches
    |G(f_max)|/√2), high-frequency gain |G(f_max)| and mean phase lag −∠G over the band [deg];
    and whether each moves as printed (cutoff and gain fall, lag grows) over every step."""
    f = np.asarray(frequency_hz, float)
    G = np.asarray(G, complex)
    mag = np.abs(G)
    hf = mag[:, -1]
    reach = mag >= hf[:, None] / math.sqrt(2)
    cutoff = f[np.argmax(reach, axis=1)]
    lag = -np.degrees(np.unwrap(np.angle(G), axis=1)).mean(1)
    lag = lag - 360.0 * np.round((lag - lag[0]) / 360.0)
    out = {"cutoff_hz": cutoff, "hf_gain": hf, "mean_lag_deg": lag}
    out["as_printed"] = {"cutoff falls": bool(np.all(np.diff(cutoff) < 0)), "gain falls": bool(np.all(np.diff(hf) < 0)),
                         "lag grows": bool(np.all(np.diff(lag) > 0))}
    return out


# ----------------------------------------------------------------------------- the model
def law_free_parameters(base, names=None) -> list:
    """Free law parameters (default all three): Ea of d [0, 60] kJ/mol and the log-linear slopes of κe
    and E [−5, 5] %/K (calibrate's default bounds), started at ``base``'s laws."""
    from physmodel.estimation.calibration import default_free_parameter

    return [default_free_parameter(base, n) for n in (names or (_EA, _SK, _SE))]


def loglinear_kappa(base):
    """``base`` with κe's water-permittivity law replaced by a log-linear law of the same slope at T_ref."""
    from physmodel.temperature import T0_K, LogLinear, water_permittivity

    t = base.T_ref - T0_K
    slope = (math.log(water_permittivity(t + 0.01)) - math.log(water_permittivity(t - 0.01))) / 0.02
    return replace(base, laws=base.laws.with_(kappa_e=LogLinear(slope=slope)))


def series_model(base, physics: dict, effects: dict, frequency_hz, temperatures_c, beam_follows_E=False):
    """``respond(values_list) -> (n_sets, n_T, F)`` physics + fixed chain [A/m] for law values.

    ``physics``: polymer values at T_ref (a0, d, κe, ...); ``effects``: {effect: {param: value}} at
    their 35 °C values; ``beam_follows_E``: the tip-driven beam's time constant scales as E(T)^−1/2."""
    from physmodel.effects import EffectModel
    from physmodel.effects.sensing import tip_driven_beam
    from physmodel.parameter_paths import apply_values
    from physmodel.temperature import T0_K

    b0 = apply_values(base, physics)
    f = np.asarray(frequency_hz, float)
    T = np.asarray(temperatures_c, float)
    s = 2j * np.pi * f
    beam = effects.get("tip_driven_beam")

    def respond(values_list):
        plist = [apply_values(b0, v) for v in values_list]
        G = EffectModel(plist, "sensor", effects).frequency_response(f, T)["S"]
        if beam_follows_E and beam is not None and beam.get("time_constant", 0.0) > 0:
            slope = np.array([p.laws.E.slope for p in plist])[:, None, None]
            tau = beam["time_constant"] * np.exp(-0.5 * slope * (T[None, :, None] - (b0.T_ref - T0_K)))
            kw = {k: beam[k] for k in ("damping", "coupling_ratio") if k in beam}
            G = G * tip_driven_beam(s, tau, **kw) / tip_driven_beam(s, beam["time_constant"], **kw)
        return G

    return respond


# ----------------------------------------------------------------------------- calibration
@dataclass
class LawCalibration:
    """Calibrated law parameters.  ``values``/``ci`` in SI ([J/mol], [1/K]); ``a0_model`` [rad⁴/s⁴]
    at the data temperatures; ``residuals`` standardised; ``result`` the engine's record."""

    result: object
    a0_model: np.ndarray
    residuals: np.ndarray
    values: dict = field(default_factory=dict)


def calibrate_laws(data: A0Series, respond, frequency_hz, free, starts: int = 3, seed: int = 0,
                   max_nfev: int = 200) -> LawCalibration:
    """Fit ``free`` law parameters so that a0 of :func:`levy_4_4` of ``respond`` matches ``data``:
    the calibration engine (:func:`~physmodel.estimation.lsq.fit_parameters`) on the a0 values as
    :class:`~physmodel.estimation.observations.ScalarObservations` (residuals ln|a0_model/a0|/σ_ln; a
    sign flip is a misfit of the magnitude only), ``max_nfev`` residual evaluations per start.  Only
    parameters a0(T) does not depend on are held at their start value; other undetermined ones keep
    their fitted value and interval.  On a misfit ``calibrate``'s policy (Birge-widened intervals,
    no identifiability verdict)."""
    from physmodel.estimation.calibration import apply_misfit_policy
    from physmodel.estimation.lsq import fit_parameters
    from physmodel.estimation.observations import ScalarObservations

    obs = ScalarObservations(data.a0, data.sigma_ln, tuple(f"a0({t:g} °C)" for t in data.temperatures_c),
                             data.temperatures_c, data.source)

    def a0_many(values_list):
        return levy_4_4(frequency_hz, respond(list(values_list)))[1][..., -1]     # (n_sets, n_T)

    res = fit_parameters(obs, None, free, starts=starts, seed=seed, predict_many=a0_many, max_nfev=max_nfev,
                         hold_undetermined="insensitive")
    res.band_hz = (float(frequency_hz[0]), float(frequency_hz[-1]))
    if not res.adequate:
        apply_misfit_policy(res, widen=True)
    a0 = a0_many([res.values])[0]
    return LawCalibration(res, a0, np.log(np.abs(a0 / data.a0)) / data.sigma_ln, dict(res.values))


# ----------------------------------------------------------------------------- the step's part
#: Calibrations run: (label, beam follows E(T), κe by the water permittivity (fixed law), free laws).
VARIANTS = (("chain fixed", False, False, (_EA, _SK, _SE)),
            ("chain fixed, κe ∝ ε_water", False, True, (_EA, _SE)),
            ("beam mode follows E(T)", True, False, (_EA, _SK, _SE)),
            ("beam mode follows E(T), κe ∝ ε_water", True, True, (_EA, _SE)),
            ("chain fixed, κe ∝ ε_water, Ea bound opened", False, True, (_EA,)))
#: Upper bound of Ea in the "bound opened" calibration (calibrate's default is 60 kJ/mol) [J/mol].
EA_OPENED = 250e3
#: Literature ranges of the laws (physics.md §7; physmodel.temperature): Ea of d, slope of E.
LITERATURE = {_EA: (10.5e3, 18e3, "Nafion conductivity and NMR self-diffusion, 10.5-18 kJ/mol (physics.md §7)"),
              _SE: (-0.0075, -0.0075, "water-soaked Nafion -0.75 %/K (DuPont; physics.md §7); seed 000 Fig. 6: "
                                      "nonlinear, numbers not printed"),
              _SK: (None, None, "water permittivity -0.45 %/K at 35 °C (Malmberg & Maryott 1956); no IPMC source")}
A0_DRAWS = 2000
#: Activation energies of d profiled (chain fixed, κe ∝ ε_water) [J/mol].
EA_PROFILE = (0.0, 10.5e3, 15e3, 18e3, 30e3, 45e3, 60e3, 90e3, 120e3, 180e3)


def _factor_ratio(name, value, t_lo=23.0, t_hi=65.0):
    """Ratio of a law's factor at t_hi over t_lo [-] for one law parameter value."""
    from physmodel.temperature import R_GAS, T0_K

    x = (-value / R_GAS * (1 / (t_hi + T0_K) - 1 / (t_lo + T0_K)) if name == _EA else value * (t_hi - t_lo))
    return math.exp(min(x, 700.0)) if math.isfinite(x) else math.nan


def run_series(base, vals, effects, sweep35, seed=0, draws=A0_DRAWS, variants=VARIANTS, prefix=""):
    """``variants`` (default all :data:`VARIANTS`) on the printed a0(T): (data, {prefix + label: dict},
    {Ea: χ²} profile)."""
    from physmodel.estimation.records import FreeParameter
    from physmodel.temperature import T0_K

    data = a0_series(sweep35, draws=draws, seed=seed)
    f = sweep35.frequency_hz
    phys = {k: v for k, v in vals.items() if "." not in k}
    out = {}
    for label, beam, water, names in variants:
        b = base if water else loglinear_kappa(base)
        free = law_free_parameters(b, names)
        if "opened" in label:
            free = [FreeParameter(_EA, 0.0, EA_OPENED, "linear", free[0].initial)]
        respond = series_model(b, phys, effects, f, data.temperatures_c, beam_follows_E=beam)
        cal = calibrate_laws(data, respond, f, free, starts=3, seed=seed)
        r = cal.result
        tr = series_model(b, phys, effects, f, TRENDS_C, beam_follows_E=beam)([cal.values])[0]
        dense_t = np.linspace(20.0, 70.0, 26)
        a0_dense = levy_4_4(f, series_model(b, phys, effects, f, dense_t, beam_follows_E=beam)(
            [cal.values, {}]))[1][..., -1]
        pct = 100 * (cal.a0_model / data.a0 - 1)
        out[prefix + label] = {"label": prefix + label, "cal": cal, "result": r, "free": names, "trends": trend_signs(f, tr),
                      "trend_response": tr, "a0_dense": (dense_t, a0_dense[0], a0_dense[1]),
                      "a0_pct": pct, "a0_rms_pct": float(np.sqrt(np.mean(pct ** 2))),
                      "a0_max_pct": float(np.abs(pct).max()),
                      "ratios": {n: (_factor_ratio(n, r.values[n]), _factor_ratio(n, r.ci_lower[n]),
                                     _factor_ratio(n, r.ci_upper[n])) for n in names},
                      "kappa_water": water, "beam": beam, "T_ref_c": b.T_ref - T0_K,
                      "defaults": {_EA: b.laws.d.activation_energy, _SE: b.laws.E.slope}}
    # χ² profile over Ea with the chain fixed and κe by the water permittivity (E does not act on a0)
    a0p = levy_4_4(f, series_model(base, phys, effects, f, data.temperatures_c)([{_EA: e} for e in EA_PROFILE]))[1]
    chi2 = np.sum((np.log(np.abs(a0p[..., -1]) / data.a0) / data.sigma_ln) ** 2, axis=1)
    return data, out, dict(zip(EA_PROFILE, chi2.tolist()))


def _slug(s):
    import re

    return re.sub(r"[^a-z0-9]+", "_", s.lower().replace("κe", "kappa").replace("ε", "eps")).strip("_")


def step_temperature(ctx, base, vals, effects, sweep35, mis35, d_row, seed=0, documented=None) -> None:
    """Run :func:`run_series` on the greedy chain's values (and, given ``documented = (values,
    effects, misfit)``, the first two variants on the documented fit: every parameter in its sourced
    range, d at 35 °C plausible or at its range's edge), write metrics, figures and the section."""
    import time

    from . import plots

    t0 = time.perf_counter()
    data, out, prof = run_series(base, vals, effects, sweep35, seed=seed)
    if documented is not None:
        out.update(run_series(base, documented[0], documented[1], sweep35, seed=seed, variants=VARIANTS[:2],
                              prefix="documented chain: ")[1])
    for ea, c2 in prof.items():
        ctx.metric(f"chain.temperature.ea_profile_chi2.{ea / 1e3:g}kJ", c2)
    ctx.metric("chain.temperature.a0_sigma_ln_identification", data.identification_ln)
    ctx.metric("chain.temperature.a0_sigma_ln_rounding_max", float(data.rounding_ln.max()))
    ctx.metric("chain.temperature.a0_printed_ratio_65_23", float(data.a0[-1] / data.a0[0]))
    for q in ("rms_db", "max_db", "rms_deg", "max_deg"):
        ctx.metric(f"chain.temperature.misfit_35c_{q}", mis35[q])
    for label, v in out.items():
        k, r = f"chain.temperature.{_slug(label)}", v["result"]
        g = r.goodness_of_fit
        for q, x in {"chi2": g.chi2, "dof": g.dof, "p_value": g.p_value, "adequate": bool(g.adequate),
                     "converged": bool(r.converged), "a0_misfit_rms_pct": v["a0_rms_pct"],
                     "a0_misfit_max_pct": v["a0_max_pct"],
                     "a0_model_ratio_65_23": float(v["cal"].a0_model[-1] / v["cal"].a0_model[0])}.items():
            ctx.metric(f"{k}.{q}", x)
        for n in v["free"]:
            p = f"{k}.{n.split('.', 1)[1].replace('.', '_')}"
            for q, x in {"": r.values[n], "_ci_lower": r.ci_lower[n], "_ci_upper": r.ci_upper[n],
                         "_identifiable": bool(r.identifiability[n].identifiable)}.items():
                ctx.metric(f"{p}{q}", x)
        for t, ok in v["trends"]["as_printed"].items():
            ctx.metric(f"{k}.trend_{_slug(t)}", ok)
    d_ok = bool(d_row["identifiable"] and d_row["inside"])
    ctx.metric("chain.temperature.d_35c", d_row["value"])
    ctx.metric("chain.temperature.d_35c_plausible", d_ok)
    ctx.metric("chain.temperature.elapsed_s", time.perf_counter() - t0)
    ctx.file(plots.a0_series(data, out, ctx.out / "chain_a0_temperature.png", (_T_DENSE, printed_a0(_T_DENSE))))
    main = out[VARIANTS[0][0]]
    curves: dict = {f"{t:g} °C, chain fixed, calibrated laws": (main["trend_response"][i] * 1e3, {"color": f"C{i}"})
              for i, t in enumerate(TRENDS_C)}
    beam = out[VARIANTS[2][0]]
    curves.update({f"{t:g} °C, beam follows E(T)": (beam["trend_response"][i] * 1e3, {"color": f"C{i}", "ls": ":"})
                   for i, t in enumerate(TRENDS_C)})
    curves["printed 35 °C model"] = (sweep35.response, {"color": "k", "lw": 2.0})
    ctx.file(plots.bode_overlay(sweep35.frequency_hz, curves, ctx.out / "chain_bode_temperatures.png",
                                      None, "physics + chain at the Fig. 5 temperatures, calibrated laws"))
    _section(ctx, data, out, prof, mis35, d_row, d_ok, time.perf_counter() - t0, documented)


def _fmt_par(r, n):
    v = r.values[n]
    unit, sc = ("kJ/mol", 1e-3) if n == _EA else ("%/K", 100.0)
    ci = (f"[{r.ci_lower[n] * sc:.3g}, {r.ci_upper[n] * sc:.3g}]" if math.isfinite(r.ci_lower[n]) else "–")
    idf = r.identifiability[n]
    return (n, f"{v * sc:.4g} {unit}", ci, "yes" if idf.identifiable else "NO", idf.reason[:120])


def _section(ctx, data, out, prof, mis35, d_row, d_ok, elapsed, documented=None):
    from physmodel.temperature import water_permittivity

    wr = float(water_permittivity(65.0) / water_permittivity(23.0))

    dt = md_table(["T [°C]", "printed a0 [1e10/s⁴]", "σ ln a0"] + [f"{v['label']}: model a0 (Δ %)" for v in out.values()],
                [(f"{t:g}", f"{a / 1e10:.4g}", f"{s:.3f}") + tuple(
                    f"{v['cal'].a0_model[i] / 1e10:.3g} ({v['a0_pct'][i]:+.1f})" for v in out.values())
                 for i, (t, a, s) in enumerate(zip(data.temperatures_c, data.a0, data.sigma_ln))])
    rows, fits, trends, impl = [], [], [], []
    for v in out.values():
        r, g = v["result"], v["result"].goodness_of_fit
        rows += [(v["label"],) + _fmt_par(r, n) for n in v["free"]]
        fits.append((v["label"], f"{g.chi2:.3g}", g.dof, f"{g.p_value:.2g}", "yes" if g.adequate else "NO",
                     "yes" if r.converged else "NO", f"{v['a0_rms_pct']:.3g}", f"{v['a0_max_pct']:.3g}"))
        trends.append((v["label"],) + tuple("yes" if ok else "NO" for ok in v["trends"]["as_printed"].values())
                      + (", ".join(f"{c:.3g}" for c in v["trends"]["cutoff_hz"]),
                         ", ".join(f"{x * 1e3:.3g}" for x in v["trends"]["hf_gain"]),
                         ", ".join(f"{x:.4g}" for x in v["trends"]["mean_lag_deg"])))
        impl.append((v["label"],) + tuple(
            (f"{v['ratios'][n][0]:.3g}" + (f" [{min(v['ratios'][n][1:]):.3g}, {max(v['ratios'][n][1:]):.3g}]"
                                           if r.identifiability[n].identifiable else " (undetermined)"))
            if n in v["ratios"] else f"{wr:.3g} (water law, fixed)" if n == _SK and v["kappa_water"]
            else f"{_factor_ratio(n, v['defaults'][n]):.3g} (default law, not fitted)" for n in (_EA, _SK, _SE)))
    lit = "; ".join(f"{n}: {s}" for n, (_, _, s) in LITERATURE.items())
    ctx.section(
        "Temperature series: the polymer's laws with the chain fixed",
        "Printed per temperature (seed 000): the full 4/4 model only at 35 °C; a0(T) (the 4/4 model's "
        "denominator constant) as a cubic fitted to the invfreqs identifications at "
        f"{', '.join(f'{t:g}' for t in data.temperatures_c)} °C; and three trends with rising T read off Fig. 5 "
        "(cutoff and high-frequency gain fall, phase lag grows).  Data: a0(T) at the fit temperatures, σ of ln a0 = "
        f"coefficient rounding (≤ {data.rounding_ln.max():.2g}) ⊕ the identification spread of an invfreqs-default "
        f"4/4 fit under the 35 °C sweep's noise ({data.identification_ln:.3g}).  Model: a0 of the same 4/4 "
        "equation-error fit of physics + chain at T, chain at its 35 °C values, polymer values at 35 °C from the "
        "chain fit; the laws move d, κe, E (and Rp ∝ T/d) from 35 °C.  At 35 °C the laws are 1, so the 35 °C "
        f"misfit is the chain fit's: {mis35['rms_db']:.3g} dB / {mis35['rms_deg']:.3g}° RMS, "
        f"{mis35['max_db']:.3g} dB / {mis35['max_deg']:.3g}° max; no other temperature has a printed response, "
        "so elsewhere the misfit is a0's.", "",
        dt, "", "Goodness of fit (χ² of the a0 residuals against its expectation; a misfit widens the intervals by "
        "the Birge ratio and withholds the identifiability verdict, as `calibrate` does):", "",
        md_table(["calibration", "χ²", "dof", "p", "fits", "converged", "a0 RMS %", "a0 max %"], fits), "",
        md_table(["calibration", "parameter", "value", "95 % interval", "determined", "why"], rows), "",
        "What the laws imply between 23 and 65 °C (factor of d, κe, E at 65 over 23 °C, with the interval where "
        "determined):", "", md_table(["calibration", "d(65)/d(23)", "κe(65)/κe(23)", "E(65)/E(23)"], impl), "",
        f"Literature: {lit}.", "",
        f"χ² profile over Ea (chain fixed, κe ∝ ε_water; {data.a0.size} a0 values, E does not act on a0): "
        + "; ".join(f"{ea / 1e3:g} kJ/mol: {c2:.3g}" for ea, c2 in prof.items()) + ".", "",
        "Printed trends (25 → 45 → 65 °C) reproduced by the calibrated model (cutoff: lowest line within 3 dB of "
        "|G(f_max)|; gain |G(f_max)| [µA/mm]; mean lag −∠G over the band [°]):", "",
        md_table(["calibration", "cutoff falls", "gain falls", "lag grows", "cutoff [Hz]", "gain", "mean lag"],
               trends), "",
        f"d at 35 °C (the chain fit): {d_row['value']:.3g} m²/s, "
        + ("determined and inside its sourced range" if d_ok else
           f"{'determined' if d_row['identifiable'] else 'undetermined'}"
           f"{'' if d_row['inside'] else ', outside its sourced range [1e-11, 1e-10] m²/s'}")
        + "; the laws are relative to 35 °C, so the temperature series cannot change d(35 °C)."
        + ("" if documented is None else
           f"  The documented chain (every parameter in its sourced range) has d = {documented[0]['d']:.3g} m²/s "
           f"at 35 °C, with a 35 °C misfit of {documented[2]['rms_db']:.3g} dB / {documented[2]['rms_deg']:.3g}° "
           "RMS; its rows above ('documented chain: ...') show what the a0(T) data say with a plausible d."), "",
        "![a0(T)](chain_a0_temperature.png)", "![Bode at 25/45/65 °C](chain_bode_temperatures.png)", "",
        f"Temperature series computed in {elapsed:.2g} s.")
