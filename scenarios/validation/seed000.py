"""Claim checks of seed 000 (Ganley et al. 2011, the IPMC sensor temperature study).

Parameter set ``seed000_sensor`` (see its module for what it was calibrated on): a0 and d fitted to
the printed 35 °C model; the C⁻ and E temperature laws chosen on the cut-off and high-frequency-gain
directions.  The phase-lag direction was not used by the law search, but on the grid it searched it
holds exactly when the cut-off direction does (``implied_by``), so its row is calibrated too.  The
preview claims (model-exact, on the printed model) and the order claims are the rows that can be
independent.
"""

from __future__ import annotations

import math

import numpy as np

from physmodel.parameter_sets import derivation as sc

from .claims import CHECKS, EXTRA_ROWS, Claim, Outcome
from .shared import ZERO_REACH, geometry_check, io_check, paper_check, rhp

SET = "seed000_sensor"
S = "sensor_seed000"


# ============================================================================ shared evaluations
def _sensor(ctx):
    return ctx.parameter_set(SET)


def _temps(ctx):
    t = ctx.pub[S]["fit_temperatures_c"]
    return [t[0], t[len(t) // 2], t[-1]] if ctx.quick else list(t)


def _misfit(ctx):
    def compute(c):
        m = sc.sensor_misfit_35c(_sensor(c))
        from dataclasses import asdict

        c.metadata["sensor_misfit_35c"] = asdict(m)
        return m
    return ctx.memo("s0:misfit", compute)


def _fits(ctx):
    """n/n rational fits (n = 1..4) to the physics over 10–100 Hz at the fit temperatures."""
    def compute(c):
        from physmodel import SensorModel
        from surrogate import RationalFit

        f = np.logspace(1, 2, 40)
        T = _temps(c)
        H = SensorModel(_sensor(c)).frequency_response(f, T)["S"][0] * 1e3
        return {n: {t: RationalFit(n, n, raise_on_failure=False).fit(f, t, H[i]) for i, t in enumerate(T)}
                for n in (1, 2, 3, 4)}
    return ctx.memo("s0:fits", compute)


def _printed_zero_split(ctx):
    from inversion import split_inverse
    from inversion.examples import seed000_sensor_35c

    return ctx.memo("s0:split", lambda c: split_inverse(seed000_sensor_35c("zeros")))


def _preview_errors(ctx):
    """Model-exact virtual experiment (the printed 35 °C model, built from its printed zeros, is the
    sensor): 20 Hz, 1 mm sine; largest decoding error [mm] with infinite preview, T_p* = 4/r0 and
    T_p*/2, away from the record ends.  The preview is passed in seconds (4/r0 computed here)."""
    def compute(c):
        from inversion import invert
        from inversion.examples import seed000_sensor_35c

        G = seed000_sensor_35c("zeros")
        dt = 2e-4 if c.quick else 1e-4
        t = np.arange(0.0, 2.0, dt)
        w = 2 * np.pi * 20.0
        g = complex(np.polyval(G.num[0][0], 1j * w) / np.polyval(G.den[0][0], 1j * w))
        current = abs(g) * np.sin(w * t + np.angle(g))
        disp = np.sin(w * t)
        m = (t > 0.6) & (t < 1.3)
        Ts = 4.0 / _printed_zero_split(c).r0
        return {k: float(np.max(np.abs(invert(G, t, current, preview=pv).output[m] - disp[m])))
                for k, pv in (("inf", "inf"), ("star", Ts), ("half", 0.5 * Ts))}
    return ctx.memo("s0:preview", compute)


def _trends(ctx):
    return ctx.memo("s0:trends", lambda c: sc.sensor_trends(_sensor(c), c.pub[S]["fit_temperatures_c"]))


# ============================================================================ checks
def c_band(ctx, value):
    lo, hi = sc.SENSOR_BAND_HZ
    return Outcome(f"calibration and trend band {lo:g}-{hi:g} Hz", "the printed band", [lo, hi] == list(value))


def c_trange(ctx, value):
    from physmodel import state_at

    st = state_at(_sensor(ctx), np.linspace(value[0], value[1], 5))
    ok = bool(np.all(np.isfinite(st.K)) and np.all(st.K > 0))
    return Outcome(f"{SET} laws evaluate on {value[0]:g}-{value[1]:g} °C (K = {st.K.min():.3g}-{st.K.max():.3g} 1/s)",
                   "every law valid over the range", ok)


def c_fit_temps(ctx, value):
    conv = [r.converged for r in _fits(ctx)[4].values()]
    return Outcome(f"4/4 fits to the physics converge at {sum(conv)}/{len(conv)} of {_temps(ctx)} °C",
                   "all converge", all(conv))


def c_order(ctx, value):
    """The order the physics needs: the lowest n/n reaching 5 % (and 1 %) relative RMS error."""
    err = {n: max(r.per_temperature[0].relative_rms_error for r in fits.values()) for n, fits in _fits(ctx).items()}
    lowest = lambda tol: min((n for n in err if err[n] <= tol), default=None)
    return Outcome("worst relative RMS error of n/n fits to the physics (10-100 Hz): "
                   + ", ".join(f"{n}/{n} {e:.2g}" for n, e in err.items())
                   + f"; lowest order within 5 %: {lowest(0.05)}/{lowest(0.05)}, within 1 %: {lowest(0.01)}/{lowest(0.01)}",
                   "fourth order is what the response needs: every n/n with n < 4 misses 5 % relative RMS error "
                   "(about 0.4 dB) at some fit temperature, 4/4 does not",
                   lowest(0.05) == 4)


def c_nmp(ctx, value):
    top = 2 * np.pi * sc.SENSOR_BAND_HZ[1]
    counts = [rhp(r.model.zeros(), top).size for r in _fits(ctx)[4].values()]
    n = sum(c > 0 for c in counts)
    return Outcome(f"{n}/{len(counts)} 4/4 fits of the physics have right-half-plane zeros within {ZERO_REACH:g}x the "
                   f"band top ({ZERO_REACH * top:.0f} rad/s; fitted over 10-100 Hz)",
                   "every fit non-minimum phase", n == len(counts))


def c_a0_poly(ctx, value):
    s = ctx.pub[S]
    c = np.array(s["a0_poly_coeffs_times_1e10"]) * 1e10
    a0_35 = float(np.polyval(c[::-1], 35.0 - s["a0_poly_center_c"]))
    printed = s["model_35c_den"][-1]
    return Outcome(f"a0(35 °C) from the polynomial = {a0_35:.4g}; printed 35 °C model a0 = {printed:.3g}",
                   "agree within the 2-significant-figure rounding of the printed 4.4e10 (+/- 1.2 %)",
                   abs(a0_35 - printed) <= 0.05e10)


def c_35c_magnitude(ctx, value):
    m = _misfit(ctx)
    return Outcome(f"{SET} vs printed 35 °C model, 10-100 Hz: magnitude RMS {m.rms_db:.2f} dB, max {m.max_db:.2f} dB",
                   "RMS <= 1 dB (the 0.5 dB per-line uncertainty given to the printed model, doubled)", m.rms_db <= 1.0)


def c_35c_phase(ctx, value):
    m = _misfit(ctx)
    return Outcome(f"{SET} vs printed 35 °C model, 10-100 Hz: phase RMS {m.rms_deg:.1f} deg, max {m.max_deg:.1f} deg",
                   "RMS <= 10 deg (the 5 deg per-line uncertainty, doubled)", m.rms_deg <= 10.0)


#: Half a unit of the last printed digit of the 35 °C numerator (-17.3, 2.2e4, -1.0e7, -9.4e8, 4.5e10).
NUM_ROUNDING = (0.05, 0.05e4, 0.05e7, 0.05e8, 0.05e10)


def _zero_ranges(num):
    """Zeros of the printed numerator and their spread over the 32 corners of its rounding box."""
    import itertools

    z0 = np.roots(num)
    corners = []
    for sgn in itertools.product((-1.0, 1.0), repeat=len(num)):
        z = np.roots(np.asarray(num) + np.asarray(sgn) * NUM_ROUNDING)
        corners.append(z[[int(np.argmin(np.abs(z - v))) for v in z0]])
    return z0, np.array(corners)


def c_zeros_printed(ctx, value):
    z0, corners = _zero_ranges(ctx.pub[S]["model_35c_num"])
    zp = complex(str(value).replace(" ", ""))
    i = int(np.argmin(np.abs(z0 - zp)))
    dist = np.abs(corners[:, i] - z0[i]).max()
    return Outcome(f"zero of the printed coefficients nearest to it: {z0[i]:.4g}; over the coefficients' rounding "
                   f"box it moves by up to {dist:.3g} rad/s; printed value off by {abs(z0[i] - zp):.3g} rad/s",
                   "printed zero within the rounding box of the printed coefficients", abs(z0[i] - zp) <= dist)


def c_preview_rule(ctx, value):
    z0, corners = _zero_ranges(ctx.pub[S]["model_35c_num"])
    pos = z0.real > 0
    r0 = float(z0[pos].real.min())
    r0_box = corners[:, pos].real.min(axis=1)
    lo, hi = float(r0_box.min()), float(r0_box.max())
    tp = 4.0 / 35.2
    return Outcome(f"printed coefficients: r0 = {r0:.4g} rad/s (rounding box {lo:.4g}-{hi:.4g}), 4/r0 = {4/r0:.4g} s; "
                   f"printed r0 = 35.2 gives 4/35.2 = {tp:.4g} s",
                   "printed r0 inside the coefficients' rounding box and T_p* = 4/r0 = 0.114 s to 3 significant figures",
                   lo <= 35.2 <= hi and round(tp, 3) == 0.114)


def c_preview_star(ctx, value):
    e = _preview_errors(ctx)
    return Outcome(f"model-exact 20 Hz, 1 mm: max error {e['star']*1e3:.3g} um with T_p* = 4/r0, "
                   f"{e['inf']*1e3:.2g} um with infinite preview ({e['star']/e['inf']:.0f}x)",
                   "'comparable': T_p* error within 2x the infinite-preview error", e["star"] <= 2 * e["inf"])


def c_preview_half(ctx, value):
    e = _preview_errors(ctx)
    ratio = e["half"] / e["star"]
    return Outcome(f"error ratio T_p*/2 vs T_p*: {ratio:.2f} (model-exact; exp(r0 T_p*/2) = e^2 = 7.39)",
                   "'threefold' at its one significant figure: 2.5-3.5", 2.5 <= ratio <= 3.5)


def _trend(key, label):
    def check(ctx, value):
        tr = _trends(ctx)
        vals = {"cutoff_decreases": tr.cutoff_hz, "hf_gain_decreases": tr.hf_gain_db,
                "phase_lag_increases": tr.phase_lag_deg}[key]
        unit = {"cutoff_decreases": "Hz", "hf_gain_decreases": "dB uA/mm", "phase_lag_increases": "deg"}[key]
        return Outcome(f"{label} at {tr.temperature_c[0]:g}/{tr.temperature_c[-1]:g} °C: {vals[0]:.2f} -> {vals[-1]:.2f} "
                       f"{unit}", "strictly monotone over the 7 fit temperatures (the paper prints a direction only)",
                       tr.monotone()[key])
    return check


def c_circuit(ctx, value):
    from physmodel import TransimpedanceChain

    g = TransimpedanceChain(value["R1_ohm"], value["R2_ohm"], value["R3_ohm_range"][1]).gain
    want = value["R3_ohm_range"][1] * value["R1_ohm"] / value["R2_ohm"]
    return Outcome(f"TransimpedanceChain gain at R3 = 50 kOhm: {g:.4g} V/A", "v2/i = R3 R1/R2",
                   math.isclose(g, want, rel_tol=1e-12))


# ============================================================================ mapping
_NOT_MEASURED = "not-checkable: the measured records are not printed"
_SMALL = ("the effect is small (the paper's Fig. 5 shows a large change but prints no number, so its size is not "
          "checkable)")
_ORDER_WHY = ("the physics' current is s times a minimum-phase charge/electrode response: over 10-100 Hz it is a smooth "
              "high-pass that a low order fits; the paper's fourth order is needed for the measured ~250 deg phase roll "
              "(three right-half-plane zeros), which the physics lacks - the same cause as the 35 °C misfit")
CHECKS.update({
    f"{S}.paper": Claim(paper_check, "reproduce", "metadata"),
    f"{S}.input": Claim(io_check("sensor", "S", "input"), "reproduce", "metadata"),
    f"{S}.output": Claim(io_check("sensor", "S", "output"), "reproduce", "metadata"),
    f"{S}.sample": Claim(geometry_check(SET, "length_mm", "width_mm", "thickness_um", 1e6), "reproduce", "input",
                         note="the printed geometry is typed into the set"),
    f"{S}.frequency_hz": Claim(c_band, "reproduce", "metadata"),
    f"{S}.temperature_range_c": Claim(c_trange, "reproduce", "metadata"),
    f"{S}.fit_temperatures_c": Claim(c_fit_temps, "reproduce", "metadata"),
    f"{S}.validation_temperatures_c": Claim(
        None, "not-checkable: the measured 35 and 45 °C responses (Figs. 8-9) are not printed; the printed 35 °C model "
              "is the calibration data of seed000_sensor", "model", SET),
    f"{S}.model_order": Claim(c_order, "finding: " + _ORDER_WHY, "model", SET),
    f"{S}.a0_poly_center_c": Claim(c_a0_poly, "reproduce", "paper", note="printed polynomial vs printed 35 °C model"),
    f"{S}.a0_poly_coeffs_times_1e10": Claim(c_a0_poly, "reproduce", "paper", note="printed polynomial vs printed 35 °C model"),
    f"{S}.model_35c_num": Claim(
        c_35c_magnitude, "finding: the printed model rises about 31 dB/decade over 10-100 Hz and peaks near 100 Hz; the "
        "sensor physics rises at most 20 dB/decade (current = s x a minimum-phase charge and electrode response); "
        "even fitted to it (a0, d free; kappa_e, r1', r2' ran to their bounds) the misfit stays", "model", SET),
    f"{S}.model_35c_den": Claim(
        c_35c_phase, "finding: the printed phase falls by about 250 deg over 10-100 Hz (three right-half-plane zeros); "
        "the physics phase stays within about 60 deg of -90 deg; a transport delay or a second sensing mechanism would "
        "be needed (discrepancy candidate); the max near 180 deg means antiphase near 100 Hz", "model", SET),
    **{f"{S}.model_35c_zeros_printed[{i}]": Claim(c_zeros_printed, "reproduce", "paper",
                                                  note="printed zeros vs printed coefficients") for i in range(4)},
    f"{S}.preview_rule": Claim(c_preview_rule, "reproduce", "paper", note="printed r0 and T_p* vs printed coefficients"),
    f"{S}.preview_claims[0]": Claim(
        c_preview_star, "finding: in a model-exact experiment the infinite-preview error is discretisation only and the "
        "T_p* error is the truncated kernel's tail (2.7 % of the amplitude); the paper's 'comparable' holds only because "
        "an experimental error of about 0.2 mm, which the physics cannot supply, dominates both", "model", None,
        "the sensor is the printed 35 °C model itself; our inversion code decodes it"),
    f"{S}.preview_claims[1]": Claim(
        c_preview_half, "finding: model-exact, halving the preview multiplies the truncation error by exp(r0 T_p*/2) = e^2 "
        "= 7.4, not 3; the paper's ~3x needs an error common to both previews (its ~0.2 mm experimental error), whose "
        "size and stimulus amplitude are not printed", "model", None,
        "the sensor is the printed 35 °C model itself; our inversion code decodes it"),
    f"{S}.trends_with_rising_temperature[0]": Claim(_trend("cutoff_decreases", "cut-off (3 dB below the in-band maximum)"),
                                                    "reproduce", "model", SET, _SMALL),
    f"{S}.trends_with_rising_temperature[1]": Claim(_trend("hf_gain_decreases", "gain at 100 Hz"), "reproduce", "model",
                                                    SET, _SMALL),
    f"{S}.trends_with_rising_temperature[2]": Claim(
        _trend("phase_lag_increases", "band-mean phase lag"), "reproduce", "model", SET,
        "not used by the law search, but no test of it either: on the whole (C- slope, E slope) grid the search "
        "covered, the lag rises exactly where the cut-off falls (both follow the Debye rate K(T), set by the C- "
        "slope); " + _SMALL, implied_by=f"{S}.trends_with_rising_temperature[0]"),
    f"{S}.inversion_experiments[0]": Claim(None, _NOT_MEASURED + " (Fig. 11)", "model", None),
    f"{S}.inversion_experiments[1]": Claim(None, _NOT_MEASURED + " (Fig. 12); its model-exact counterpart is preview_claims[0]",
                                           "model", None),
    f"{S}.inversion_experiments[2]": Claim(None, _NOT_MEASURED + " (Fig. 13)", "model", None),
    f"{S}.inversion_experiments[3]": Claim(None, _NOT_MEASURED + " (Fig. 14); tests/inversion covers the model-exact free "
                                           "vibration", "model", None),
    f"{S}.inversion_experiments[4]": Claim(None, _NOT_MEASURED + " (Fig. 15); tests/inversion covers the model-exact free "
                                           "vibration", "model", None),
    f"{S}.circuit": Claim(c_circuit, "reproduce", "metadata", note="the printed circuit law, typed in"),
})

EXTRA_ROWS[f"{S}.model_order"] = [(
    "nonminimum_phase", "the fitted 4/4 models G_T(s) are of nonminimum phase (zeros with positive real parts)",
    Claim(c_nmp, "finding: the physics' 4/4 fits over 10-100 Hz have a zero at s = 0 and left-half-plane zeros, not the "
          "printed right-half-plane zeros (35.2, 662 +/- 498j rad/s); " + _ORDER_WHY.split(";")[0], "model", SET))]
