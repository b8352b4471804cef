"""Seed paper 001 (IPMC actuator under changing temperature): open-loop tracking at 45 degC.

Published claims (Dong and Tan 2012, Sec. 3; physmodel/parameter_sets/published.toml, [actuator_seed001]): a proper third-order model
(3 zeros, 3 poles; k, zeros and poles quadratic in T, fitted on 8 of the 10 bath temperatures,
35 and 45 degC held out) is inverted with the stable noncausal algorithm to track 0.65 mm
references at 45 degC: a 0.5 Hz sine, a 2 Hz sine and 0.325 (sin(pi t) + sin(4 pi t)) mm.
Scheme 1 inverts the model fitted at 19 degC, scheme 2 the temperature-scheduled model
evaluated at 45 degC.  "At 0.5 Hz scheme 2 is only slightly better; for 2 Hz and the two-tone
reference its error bound is less than half of scheme 1's", because "the effect of the
temperature is much more pronounced at 2 Hz than at 0.5 Hz".

Virtual experiment (the oracle is independent of the package under test):

* plant: physmodel's Chen-Tan actuator with the calibrated seed 001 set (``seed001_actuator``:
  its E and C- law are solved from the printed trend, 19 degC about 7 dB above 55 degC near
  3 Hz); its time response comes from
  ``physmodel.data.timesim.simulate`` (vector-fitted realisation of the exact transfer function
  to 1e-4, exact FOH simulation);
* surrogates: the paper's data set synthesised from the same physics (30 log-spaced lines,
  0.1-9 Hz, the paper's ten temperatures, noise-free, mm/V), fitted with
  ``surrogate.RationalFit(3, 3)`` at 19 degC (scheme 1) and ``surrogate.ScheduledFit("zpk",
  3, 3, degree=2)`` on the 8 training temperatures (scheme 2); both converge;
* feedforward: ``inversion.feedforward(G, t, d, preview="inf", limits="off")`` (the paper's tracking
  experiments use the full noncausal inverse; the virtual plant takes any voltage), applied to
  the plant at 45 degC;
* error bound: max |y - d| over [T/3, T - 0.5 s] of a T = 12 s record sampled at 1 kHz (after
  the start transient; before the record end, where the noncausal inverse sees the reference
  stop).

Measured (mm; error bound scheme 1 / scheme 2, ratio):
  0.5 Hz    0.126 / 0.068    0.54   -> "scheme 2 only slightly better" NOT reproduced
  2 Hz      0.203 / 0.066    0.33   -> "less than half" reproduced
  two-tone  0.162 / 0.067    0.41   -> "less than half" reproduced
The plant was calibrated on the 19-vs-55 degC trend only (7 dB at 3 Hz), so the 2 Hz and two-tone
results are predictions.  At 0.5 Hz scheme 2 nearly halves the error as well: the physics'
19 -> 45 degC change of |M| there (~10 %, about half the 2 Hz change) is as large as the 3/3 fits'
structural error, and the scheduled model removes it.  "Only slightly better" is read against the
paper's "significantly better ... less than half" at 2 Hz as an improvement of at most a quarter
(ratio >= 0.75); the test asserts the measured disagreement.

Also checked: the time-domain error bounds of the sines equal the steady-state prediction
A |P(jw)/G(jw) - 1| from the physics frequency response (oracle consistency), and the
preview rule T_p = 4/r0 (passed in seconds) is far too short for these surrogates: their anti-stable
residues are large (|r| ~ 3.7e3 V/mm/s at |z| ~ 76 rad/s, i.e. |r|/|z| ~ 48 V/mm against
|1/G| ~ 0.3-0.6 V/mm), so even the exp(-4) tail exceeds the inverse itself (0.77 V error
on a 4.1 V feedforward at 2 Hz); the feedforward error then matches the closed-form
truncation gain, and 10/r0 brings it below 1e-3 of the feedforward.
"""

import numpy as np
import pytest
import scipy.signal as ss

import physmodel
import surrogate
from inversion import feedforward, split_inverse
from physmodel.data.sweep import synthesize_sweep
from physmodel.data.timesim import model_realization, simulate

TEMPS_C = [19.0, 21.5, 23.3, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0]
HELD_OUT_C = (35.0, 45.0)
F_HZ = np.logspace(np.log10(0.1), np.log10(9.0), 30)
T_TRACK = 45.0
AMP_MM = 0.65
DT = 1e-3
T_REC = 12.0
REFERENCES = {
    "0.5 Hz": lambda t: AMP_MM * np.sin(np.pi * t),
    "2 Hz": lambda t: AMP_MM * np.sin(4 * np.pi * t),
    "two-tone": lambda t: 0.5 * AMP_MM * (np.sin(np.pi * t) + np.sin(4 * np.pi * t)),
}


@pytest.fixture(scope="module")
def plant():
    return physmodel.ActuatorModel(physmodel.get_parameter_set("seed001_actuator"))


def _plant_mm_per_v(plant, f_hz, T):
    return plant.frequency_response(np.atleast_1d(f_hz), [T])["M"][0, 0] * 1e3


def _tf_at(G, f_hz):
    return np.array([complex(G(2j * np.pi * f)) for f in np.atleast_1d(f_hz)])


@pytest.fixture(scope="module")
def fits(plant):
    sw = synthesize_sweep(plant, "M", F_HZ, TEMPS_C)          # mm/V, noise-free
    T, F, H = sw.temperature_c, sw.frequency_hz, sw.response
    k19 = T == 19.0
    train = ~np.isin(T, HELD_OUT_C)
    assert np.unique(T[train]).size == 8
    r1 = surrogate.RationalFit(3, 3).fit(F[k19], T[k19], H[k19])
    r2 = surrogate.ScheduledFit(form="zpk", n_zeros=3, n_poles=3, degree=2).fit(
        F[train], T[train], H[train])
    k45 = T == T_TRACK
    r45 = surrogate.RationalFit(3, 3).fit(F[k45], T[k45], H[k45])
    return {"r1": r1, "r2": r2, "r45": r45,
            "scheme 1": r1.model.at(19.0), "scheme 2": r2.model.at(T_TRACK),
            "direct 45": r45.model.at(T_TRACK)}


@pytest.fixture(scope="module")
def tracking(plant, fits):
    t = np.arange(0.0, T_REC + DT / 2, DT)
    window = (t >= T_REC / 3) & (t <= T_REC - 0.5)
    real = model_realization(plant, T_TRACK, 1.0 / DT, t[-1])
    bounds, volts = {}, {}
    for ref, fn in REFERENCES.items():
        d = fn(t)
        for scheme in ("scheme 1", "scheme 2"):
            # a virtual plant: the paper's 0.65 mm references ask up to 16.5 V of these surrogates
            # (beyond the default 3 V limit); the claims are about tracking
            ff = feedforward(fits[scheme], t, d, preview="inf", limits="off")          # volts
            y = simulate(plant, T_TRACK, t, ff.output, realization=real).output * 1e3   # m -> mm
            bounds[ref, scheme] = float(np.max(np.abs(y - d)[window]))
            volts[ref, scheme] = ff.output
    return t, window, bounds, volts


def test_both_fits_converge_and_are_non_minimum_phase(fits):
    for key in ("r1", "r2", "r45"):
        assert fits[key].converged, fits[key].status
    for key in ("scheme 1", "scheme 2"):
        G = fits[key]
        z = G.zeros()
        assert z.size == 3 and G.poles().size == 3                   # proper third order
        rhp = z[z.real > 0]
        # the paper's finding: a complex pair of right-half-plane zeros at every temperature
        assert rhp.size == 2 and np.all(np.abs(rhp.imag) > 0)
        assert np.all(G.poles().real < 0)


def test_scheduled_model_predicts_the_held_out_temperature_like_a_direct_fit(fits):
    # paper, Fig. 4: at 45 degC (not used in the scheduled fit) the scheduled model is an
    # excellent approximation of the model fitted directly at 45 degC
    g_s = _tf_at(fits["scheme 2"], F_HZ)
    g_d = _tf_at(fits["direct 45"], F_HZ)
    assert np.max(np.abs(g_s / g_d - 1)) < 0.05


def test_temperature_effect_is_much_larger_at_2hz_than_at_half_hz(plant):
    # the paper's explanation of the tracking results (Sec. 3, 'much more pronounced at 2 Hz than at
    # 0.5 Hz'), checked on the plant itself; 'much more' read as at least 1.5x (measured 1.8x:
    # 0.096 and 0.175)
    eff = {f: abs(_plant_mm_per_v(plant, f, T_TRACK)[0] / _plant_mm_per_v(plant, f, 19.0)[0] - 1)
           for f in (0.5, 2.0)}
    assert eff[2.0] > 1.5 * eff[0.5]


@pytest.mark.parametrize("ref, f_hz", [("0.5 Hz", 0.5), ("2 Hz", 2.0)])
@pytest.mark.parametrize("scheme", ["scheme 1", "scheme 2"])
def test_error_bounds_match_the_steady_state_prediction(plant, fits, tracking, ref, f_hz, scheme):
    # independent consistency check of the whole chain: the steady-state tracking error of a
    # sine is A |P(jw)/G(jw) - 1|, P from the physics frequency response (measured: within
    # 4 %, the rest is the decaying start transient)
    _, _, bounds, _ = tracking
    ratio = _plant_mm_per_v(plant, f_hz, T_TRACK)[0] / _tf_at(fits[scheme], f_hz)[0]
    pred = AMP_MM * abs(ratio - 1)
    assert bounds[ref, scheme] == pytest.approx(pred, rel=0.08)


@pytest.mark.parametrize("ref", ["2 Hz", "two-tone"])
def test_scheme2_error_bound_is_less_than_half_of_scheme1(tracking, ref):
    _, _, bounds, _ = tracking
    e1, e2 = bounds[ref, "scheme 1"], bounds[ref, "scheme 2"]
    assert e2 < 0.5 * e1, f"{ref}: scheme 1 {e1:.4f} mm, scheme 2 {e2:.4f} mm"
    assert e2 < 0.2 * AMP_MM                        # measured 0.066 and 0.067 mm


def test_half_hz_only_slightly_better_is_not_reproduced(tracking):
    """Printed: 'at 0.5 Hz scheme 2 is only slightly better'.  Measured: better, but by nearly half
    (ratio 0.54), i.e. not 'slightly' (ratio >= 0.75, see the module docstring)."""
    _, _, bounds, _ = tracking
    e1, e2 = bounds["0.5 Hz", "scheme 1"], bounds["0.5 Hz", "scheme 2"]
    assert e2 < e1                                   # scheme 2 is better ...
    assert e2 < 0.75 * e1, "the 0.5 Hz claim now holds: update the docstring and ipmc validate"


def test_4_over_r0_preview_is_too_short_for_these_surrogates(fits, tracking):
    # T_p* = 4/r0 bounds the neglected tail by exp(-4) of the anti-stable *kernel*, but here
    # |r_i|/|p_i| ~ 48 V/mm against |1/G(jw)| ~ 0.3-0.6 V/mm, so the truncation error exceeds
    # the inverse itself.
    # The steady-state feedforward error is A |E(jw)| with
    # E = sum_rhp r_i exp((jw - p_i) T_p)/(jw - p_i)
    # (tail of the anticausal kernel beyond T_p, from scipy.signal.residue).
    t, window, _, volts = tracking
    G = fits["scheme 2"]
    num, den = np.asarray(G.num[0][0], float), np.asarray(G.den[0][0], float)
    r, p, _ = ss.residue(den, num)
    rhp = p.real > 0
    w = 4 * np.pi
    d = REFERENCES["2 Hz"](t)
    v_inf = volts["2 Hz", "scheme 2"]
    sp = split_inverse(G)
    for mult in (4.0, 10.0):
        ff = feedforward(sp, t, d, preview=mult / sp.r0, limits="off")    # a too-short preview: tens of V
        E = np.sum(r[rhp] * np.exp((1j * w - p[rhp]) * ff.preview_s) / (1j * w - p[rhp]))
        dv = np.max(np.abs(ff.output - v_inf)[window])
        assert dv == pytest.approx(AMP_MM * abs(E), rel=0.05)
        if mult == 4.0:
            assert abs(E) > abs(1 / _tf_at(G, 2.0)[0])      # error larger than the inverse itself
        else:
            assert dv < 1e-3 * np.max(np.abs(v_inf))
