"""Claim checks of seed 001 (Dong and Tan 2012, the IPMC actuator temperature study).

Parameter set ``seed001_actuator``: E at T_ref and a C⁻ law solved from the 19-vs-55 °C trend only
(``trends[1]``: 7 dB at about 3 Hz, 19 °C larger).  The order claims and the right-half-plane zero
pair are predictions of the physics.  The 35/45 °C hold-out of the scheduled model and the 45 °C
tracking comparison are round trips: a surrogate fitted to the noise-free physics is compared with
another fit to it, or inverted to drive the very plant it was fitted to.  They pass with the
uncalibrated ``seed001_actuator_dev`` (whose 19-vs-55 °C difference has the wrong sign) and with the
C⁻ slope's sign flipped (tests/scenarios/test_validate.py), so they test our fitting and inversion
code, not the physics against the paper.
"""

from __future__ import annotations

import math

import numpy as np

from physmodel.parameter_sets import derivation as sc

from .claims import CHECKS, EXTRA_ROWS, Claim, Outcome
from .shared import VISIBLE_MISFIT, ZERO_REACH, geometry_check, io_check, paper_check, rhp

SET = "seed001_actuator"
S = "actuator_seed001"


# ============================================================================ shared evaluations
def _temps(ctx):
    t = ctx.pub[S]["temperatures_c"]
    return [t[0], 35.0, t[-1]] if ctx.quick else list(t)


def _sweep(ctx):
    def compute(c):
        from physmodel import ActuatorModel
        from physmodel.data.sweep import synthesize_sweep

        return synthesize_sweep(ActuatorModel(c.parameter_set(SET)), "M", sc.seed001_frequencies_hz(),
                                c.pub[S]["temperatures_c"])
    return ctx.memo("s1:sweep", compute)


def _orders(ctx):
    """{(n_zeros, n_poles): {T: FitResult}} for the orders the paper compares (noise-free physics)."""
    def compute(c):
        from surrogate import RationalFit

        sw = _sweep(c)
        out = {}
        for order in ((2, 2), (3, 3), (2, 3), (4, 4)):
            fitter = RationalFit(*order, raise_on_failure=False)
            out[order] = {t: fitter.fit(sw.select(t).frequency_hz, t, sw.select(t).response) for t in _temps(c)}
        return out
    return ctx.memo("s1:orders", compute)


def _err(ctx, order) -> np.ndarray:
    return np.array([r.per_temperature[0].relative_rms_error for r in _orders(ctx)[order].values()])


def _schedule(ctx):
    """The paper's procedure on the physics: zpk 3/3, quadratic in T, 8 temperatures; the scheduled model
    at 35 and 45 °C against the direct 3/3 fits there (max relative difference over the grid)."""
    def compute(c):
        from surrogate import RationalFit, fit_sweep

        val = c.pub[S]["validation_temperatures_c"]
        sw = _sweep(c)
        res = fit_sweep(sw.exclude(val), 3, 3, degree=2, form="zpk", raise_on_failure=False)
        diff = {}
        for t in val:
            d = sw.select(t)
            direct = RationalFit(3, 3, raise_on_failure=False).fit(d.frequency_hz, t, d.response)
            hs = res.model.frequency_response(d.frequency_hz, t)
            diff[t] = float(np.max(np.abs(hs / direct.model.frequency_response(d.frequency_hz) - 1)))
        return res, diff
    return ctx.memo("s1:schedule", compute)


#: The printed tracking references at 45 °C (0.65 mm amplitude) [mm] as functions of t [s].
REFERENCES = {"0.5 Hz": lambda t: 0.65 * np.sin(np.pi * t), "2 Hz": lambda t: 0.65 * np.sin(4 * np.pi * t),
              "two-tone": lambda t: 0.325 * (np.sin(np.pi * t) + np.sin(4 * np.pi * t))}


def _tracking(ctx):
    """Virtual tracking experiment at 45 °C: the physics is the plant; scheme 1 inverts a 3/3 fit at 19 °C,
    scheme 2 the scheduled zpk model at 45 °C (fitted without 35/45 °C); full noncausal inverse
    (preview "inf", as in the paper's experiments).  Error bound: max |y - d| over [T/3, T - 0.5 s] of a
    12 s record at 1 kHz.  Returns {reference: (bound scheme 1, bound scheme 2)} [mm]."""
    def compute(c):
        from inversion import feedforward
        from physmodel import ActuatorModel
        from physmodel.data.timesim import model_realization, simulate
        from surrogate import RationalFit

        plant = ActuatorModel(c.parameter_set(SET))
        d19 = _sweep(c).select(19.0)
        g1 = RationalFit(3, 3).fit(d19.frequency_hz, 19.0, d19.response).model.at(19.0)
        g2 = _schedule(c)[0].model.at(45.0)
        dt, T = 1e-3, 12.0
        t = np.arange(0.0, T + dt / 2, dt)
        win = (t >= T / 3) & (t <= T - 0.5)
        real = model_realization(plant, 45.0, 1.0 / dt, t[-1])
        out = {}
        for ref, fn in REFERENCES.items():
            d = fn(t)
            # the paper's 0.65 mm references ask this virtual plant for more than the 3 V default
            # limit; the claims are about tracking, so the limit is off
            b = [float(np.max(np.abs(simulate(plant, 45.0, t, feedforward(g, t, d, preview="inf", limits="off").output,
                                              realization=real).output * 1e3 - d)[win])) for g in (g1, g2)]
            out[ref] = tuple(b)
        return out
    return ctx.memo("s1:tracking", compute)


# ============================================================================ checks
def c_excitation(ctx, value):
    f = sc.seed001_frequencies_hz()
    return Outcome(f"seed 001 grid: {f.size} log-spaced lines {f[0]:g}-{f[-1]:g} Hz", "30 lines, 0.1-9 Hz",
                   f.size == 30 and math.isclose(f[0], 0.1) and math.isclose(f[-1], 9.0))


def c_temps(ctx, value):
    T = _sweep(ctx).temperatures().tolist()
    return Outcome(f"physics sweeps at {len(T)} temperatures {T[0]:g}-{T[-1]:g} °C", "all printed temperatures",
                   sorted(T) == sorted(float(v) for v in value))


def c_validation(ctx, value):
    res, diff = _schedule(ctx)
    txt = ", ".join(f"{t:g} °C: {diff[t]:.3f}" for t in value)
    return Outcome(f"scheduled zpk model (fitted without 35/45 °C) vs a direct 3/3 fit there, max |G_s/G_d - 1| over "
                   f"the 30 lines: {txt}",
                   "'excellent approximation to the directly fitted model': within 5 % (0.4 dB) at every line",
                   res.converged and all(v <= 0.05 for v in diff.values()))


def c_model(ctx, value):
    res, _ = _schedule(ctx)
    fits = [e.fit_percent for e in res.per_temperature]
    return Outcome(f"zpk 3/3, quadratic in T, fitted on 8 temperatures: {'converged' if res.converged else 'NOT converged'}, "
                   f"stable={res.stability.stable}, fit {min(fits):.1f}-{max(fits):.1f} %", "converged and stable",
                   res.converged and res.stability.stable)


def c_order_2(ctx, value):
    e2, e3 = _err(ctx, (2, 2)), _err(ctx, (3, 3))
    return Outcome(f"relative RMS error 2/2: {e2.min():.3f}-{e2.max():.3f}, 3/3: {e3.min():.3f}-{e3.max():.3f}",
                   f"'clearly worse': 2/2 error >= 2x the 3/3 error and >= {VISIBLE_MISFIT:g} (visible) at every "
                   "temperature", bool(np.all(e2 >= 2 * e3) and np.all(e2 >= VISIBLE_MISFIT)))


def c_order_4(ctx, value):
    e3, e4 = _err(ctx, (3, 3)), _err(ctx, (4, 4))
    big = []
    for r in _orders(ctx)[(4, 4)].values():
        p = np.abs(np.asarray(r.model.poles()))
        big.append(p.max() > 10 * np.sort(p)[-2])
    return Outcome(f"4/4 error {e4.min():.4f}-{e4.max():.4f} vs 3/3 {e3.min():.3f}-{e3.max():.3f}; "
                   f"very large negative pole in {sum(big)}/{len(big)} fits",
                   "'adds little': 4/4 error >= 0.5x the 3/3 error at every temperature", bool(np.all(e4 >= 0.5 * e3)))


def c_order_strict(ctx, value):
    e3, e23 = _err(ctx, (3, 3)), _err(ctx, (2, 3))
    return Outcome(f"strictly proper 2/3 error {e23.min():.3f}-{e23.max():.3f} vs proper 3/3 {e3.min():.3f}-{e3.max():.3f}",
                   "2/3 error >= the 3/3 error (to the fitter's 1e-3 relative tolerance) at every temperature",
                   bool(np.all(e23 >= e3 * (1 - 1e-3))))


def c_nmp(ctx, value):
    top = 2 * np.pi * float(sc.seed001_frequencies_hz()[-1])
    n = []
    for r in _orders(ctx)[(3, 3)].values():
        z = rhp(r.model.zeros(), top)
        n.append(z.size == 2 and bool(np.all(np.abs(z.imag) > 0)))
    pair = rhp(next(iter(_orders(ctx)[(3, 3)].values())).model.zeros(), top)
    return Outcome(f"complex RHP zero pair within {ZERO_REACH:g}x the band top ({ZERO_REACH * top:.0f} rad/s) in "
                   f"{sum(n)} of {len(n)} 3/3 fits (e.g. {_temps(ctx)[0]:g} °C: "
                   f"{', '.join(f'{v:.3g}' for v in pair) or 'none'}{' rad/s' if pair.size else ''})",
                   "at every temperature; a zero beyond the reach of the 0.1-9 Hz data or numerically infinite "
                   "is not counted", all(n))


def c_resonance(ctx, value):
    r = sc.actuator_trends(ctx.parameter_set(SET), ctx.pub[S]["temperatures_c"]).resonance_hz
    return Outcome(f"peak of |M|: {r[0]:.2f} Hz at 19 °C -> {r[-1]:.2f} Hz at 55 °C", "strictly decreasing over the 10 "
                   "temperatures", bool(np.all(np.diff(r) < 0)))


def c_7db(ctx, value):
    t = sc.actuator_trends(ctx.parameter_set(SET), ctx.pub[S]["temperatures_c"])
    return Outcome(f"largest |M(19 °C)| - |M(55 °C)| = {t.max_difference_db:+.2f} dB at {t.at_hz:.2f} Hz",
                   "'about 7 dB' at 1 significant figure: +6.5 to +7.5 dB (19 °C larger), 'about 3 Hz': 2.5-3.5 Hz",
                   6.5 <= t.max_difference_db <= 7.5 and 2.5 <= t.at_hz <= 3.5)


def c_tracking_halves(ctx, value):
    b = _tracking(ctx)
    r = {k: b[k][1] / b[k][0] for k in ("2 Hz", "two-tone")}
    return Outcome("virtual experiment, error bound scheme 1 / scheme 2 [mm]: "
                   + "; ".join(f"{k} {b[k][0]:.3f} / {b[k][1]:.3f} (ratio {r[k]:.2f})" for k in r),
                   "'less than half': ratio < 0.5 for the 2 Hz and the two-tone references", all(v < 0.5 for v in r.values()))


def c_tracking_half_hz(ctx, value):
    b = _tracking(ctx)["0.5 Hz"]
    ratio = b[1] / b[0]
    return Outcome(f"virtual experiment, 0.5 Hz error bound scheme 1 / scheme 2: {b[0]:.3f} / {b[1]:.3f} mm (ratio {ratio:.2f})",
                   "'only slightly better' (set against 'significantly better ... less than half' at 2 Hz): scheme 2 "
                   "better by at most a quarter, ratio 0.75-1.0", 0.75 <= ratio <= 1.0)


# ============================================================================ mapping
_NOT_MEASURED = "not-checkable: the measured records are not printed"
_ROUND_TRIP_SCHEDULE = ("the scheduled and the direct model are both fitted to the same noise-free physics, so the row "
                        "checks the zpk schedule's interpolation in T, not the physics against the paper; it passes "
                        "with the uncalibrated seed001_actuator_dev and with the C- slope's sign flipped")
_ROUND_TRIP_TRACKING = ("virtual experiment: scheme 2 inverts a surrogate of the very plant it drives (the physics), "
                        "scheme 1 one fitted at 19 °C; scheme 2 wins whenever the plant changes between 19 and 45 °C, "
                        "in either direction: the 2 Hz/two-tone ratios stay below 0.5 with the uncalibrated "
                        "seed001_actuator_dev and with the C- slope's sign flipped (19-vs-55 °C trend of the wrong sign)")
CHECKS.update({
    f"{S}.paper": Claim(paper_check, "reproduce", "metadata"),
    f"{S}.input": Claim(io_check("actuator", "M", "input"), "reproduce", "metadata"),
    f"{S}.output": Claim(io_check("actuator", "M", "output"), "reproduce", "metadata"),
    f"{S}.sample": Claim(geometry_check(SET, "free_length_mm", "width_mm", "thickness_mm", 1e3), "reproduce", "input",
                         note="the printed geometry is typed into the set"),
    f"{S}.excitation": Claim(c_excitation, "reproduce", "metadata"),
    f"{S}.temperatures_c": Claim(c_temps, "reproduce", "metadata"),
    f"{S}.validation_temperatures_c": Claim(c_validation, "reproduce", "round-trip", SET, _ROUND_TRIP_SCHEDULE),
    f"{S}.model": Claim(c_model, "reproduce", "metadata", note="the paper's procedure runs on the physics"),
    f"{S}.order_claims[0]": Claim(c_order_2, "reproduce", "model", SET),
    f"{S}.order_claims[1]": Claim(
        c_order_4, "finding: the physics' charge dynamics add a second slow real pole; a 4/4 fit captures it and beats "
        "3/3 by an order of magnitude (no very large pole); measured noise would hide part of that gain", "model", SET),
    f"{S}.order_claims[2]": Claim(c_order_strict, "reproduce", "paper",
                                  note="true for any data: 2/3 is the 3/3 class with b3 = 0, so the least-squares 3/3 fit "
                                       "is never worse; the row checks the fitter, not the physics"),
    f"{S}.nonminimum_phase": Claim(c_nmp, "reproduce", "model", SET),
    f"{S}.trends[0]": Claim(c_resonance, "reproduce", "input",
                            note="the first mode scales as sqrt(E(T)); the modulus law (-0.75 %/K, physics.md default) is "
                                 "a model input, so the falling resonance follows from it by construction"),
    f"{S}.trends[1]": Claim(c_7db, "reproduce", "model", SET),
    f"{S}.tracking_experiments": Claim(None, _NOT_MEASURED + " (hardware tracking, Figs. 6-8)", "model", SET),
    f"{S}.tracking_claims[0]": Claim(None, "not-checkable: describes the experimental schemes (hardware); "
                                     "tracking_claims[1] runs them on the physics", "metadata"),
    f"{S}.tracking_claims[1]": Claim(c_tracking_halves, "reproduce", "round-trip", SET, _ROUND_TRIP_TRACKING),
})

EXTRA_ROWS[f"{S}.tracking_claims[1]"] = [(
    "half_hz", "at 0.5 Hz scheme 2 is only slightly better",
    Claim(c_tracking_half_hz, "finding: in the virtual experiment scheme 2 nearly halves the 0.5 Hz error too: the "
          "physics' 19-to-45 °C change of |M| at 0.5 Hz (about 10 %, half its 2 Hz change) is as large as the 3/3 fits' "
          "structural error there, and the scheduled model removes it; 'only slightly better' implies a 0.5 Hz change "
          "small next to the hardware's other errors, which the physics (calibrated at 3 Hz only) does not have",
          "round-trip", SET, _ROUND_TRIP_TRACKING))]
