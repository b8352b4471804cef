"""Reproducible derivation of the calibrated seed sets ``seed000_sensor`` and ``seed001_actuator``.

Run ``python3 -m physmodel.parameter_sets.derivation`` (a few seconds) to re-derive the numbers stored in
:mod:`physmodel.parameter_sets`; nothing here runs at import.  The trend metrics below are also
what :mod:`scenarios.validation` and the tests use to check the stored sets against the seeds.

Seed 000 sensor (18 × 6.5 × 0.21 mm Nafion-117)
    *Data.*  The only printed response is the 35 °C fourth-order model (Sec. IV-A); it is treated
    as measured data over the paper's band, 10–100 Hz (:func:`printed_sensor_sweep`), with a per-line
    uncertainty of 0.5 dB / 5° (the coefficients are printed to 2–3 significant figures).
    *Fit.*  :func:`physmodel.estimation.calibration.calibrate` (kind "sensor", kernel "boundary_charge") frees the
    sensing coupling a0 (printed nowhere), the diffusivity d, the permittivity κe and the electrode
    resistances r1', r2' (:data:`SENSOR_FREE`), with ``T_ref`` = 35 °C so the temperature laws do not
    enter.  κe, r1' and r2' run to their bounds and are held at the development values
    (``hold_undetermined="always"``): the printed model cannot be followed within its stated
    uncertainty (χ² ≈ 6000 on 57 degrees of freedom), and holding the three raises the cost from
    3028 to 3625 against the +441 the hold test allows under that misfit; the stored set keeps the
    development values on purpose, and ``result.holds`` records the cost.  a0 is negative: the printed phase at 10 Hz (−58°) is within 90° of the physics phase for
    a0 < 0 (≈ −90° minus the electrode lag) and 150° from a0 > 0.
    *Laws.*  No quantitative trend is printed, only directions (cut-off frequency and 100 Hz gain
    falling, phase lag rising with T).  With the default Arrhenius diffusivity the Debye rate K rises
    with T and the cut-off *rises*; a falling K needs a falling fixed-charge concentration C⁻ (water
    uptake dilutes it), the one law-able knob for it.  Two slopes are free (C⁻, E), so two directions
    are used, each on the knob that mainly controls it: :func:`choose_sensor_laws` takes the smallest
    departure from the physics.md defaults on a grid of (C⁻ slope, E slope) that makes the cut-off
    and the 100 Hz gain fall strictly over the seven fit temperatures (:data:`SENSOR_CALIBRATION_TRENDS`).
    The phase-lag direction is not used, but it is no prediction: it and the cut-off both follow K(T),
    and on every slope pair of the grid the lag rises exactly when the cut-off falls.

Seed 001 actuator (45 mm free length × 11 × 0.3 mm, in water)
    *Data.*  The zpk schedules' numbers are not in the text; what is printed is the trend: the
    largest magnitude difference between 19 and 55 °C is about 7 dB near 3 Hz, 19 °C larger, and
    the resonance moves down with T.
    *Fit.*  Only ``trends[1]`` of the published claims is used.  Two equations — D(3 Hz) = 7 dB and
    dD/dln f (3 Hz) = 0 with D = |M(19 °C)| − |M(55 °C)| in dB — in two unknowns: the modulus at ``T_ref`` (sets the first mode) and the slope of a log-linear C⁻
    law (the only law-able knob that lowers the actuation gain with T; with default laws the gain near
    2 Hz rises with T because E falls and d rises).  The modulus keeps the physics.md default slope
    −0.75 %/K (DuPont), which moves the resonance down.  These are feature targets, not a response,
    so they are solved with ``scipy.optimize.least_squares`` directly (:func:`solve_actuator_trend`).
    The resonance shift follows from the modulus-law input; the order claims and the right-half-plane
    zero pair are predictions; the 35/45 °C hold-out and the 45 °C tracking comparison are round trips
    (a surrogate of the physics against the physics), not predictions.

Which claims each set was calibrated on is recorded in the ``CALIBRATION`` table of its module
(:mod:`~physmodel.parameter_sets.seed000`, :mod:`~physmodel.parameter_sets.seed001`); ``ipmc validate``
gives these rows, and rows a test shows they imply, the basis "calibrated"; a model row that uses the set is
otherwise "independent", unless it compares a surrogate of the set with the set ("round-trip").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..actuator import ActuatorModel
from ..data.sweep import FrequencySweep
from ..errors import IPMCError
from ..sensor import SensorModel
from ..temperature import LogLinear
from . import get_parameter_set
from .published import seed000_printed_model_35c

#: Seed 000, Sec. IV-A: the printed 35 °C model, tip displacement [mm] → current [µA], s in rad/s.
SEED000_NUM_35C, SEED000_DEN_35C, _ = seed000_printed_model_35c()

SENSOR_BAND_HZ = (10.0, 100.0)
SENSOR_T_CAL_C = 35.0
SENSOR_FIT_TEMPERATURES_C = (23.0, 25.0, 30.0, 40.0, 50.0, 60.0, 65.0)
#: Per-line uncertainty given to the printed model's response when used as data [dB], [deg].
PRINTED_STD_DB, PRINTED_STD_DEG = 0.5, 5.0
#: (name, lower, upper) of the sensor's free parameters (log scale; a0 keeps its negative sign).
SENSOR_FREE = (("a0", -1e3, -1e-4), ("d", 1e-15, 1e-9), ("kappa_e", 1e-8, 1e-3),
               ("r1_sheet", 1e-2, 1e5), ("r2_specific", 1e-8, 1e2))

ACTUATOR_TEMPERATURES_C = (19.0, 21.5, 23.3, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0, 55.0)
ACTUATOR_TARGET_DB, ACTUATOR_TARGET_HZ = 7.0, 3.0


def seed001_frequencies_hz() -> np.ndarray:
    """Seed 001's excitation grid: 30 log-spaced frequencies 0.1–9 Hz."""
    return np.logspace(-1.0, math.log10(9.0), 30)


# ============================================================================ sensor: data and fit
def printed_sensor_response(frequency_hz) -> np.ndarray:
    """The printed 35 °C model at ``frequency_hz`` [Hz], complex [µA/mm]."""
    s = 2j * np.pi * np.asarray(frequency_hz, dtype=float)
    return np.polyval(SEED000_NUM_35C, s) / np.polyval(SEED000_DEN_35C, s)


def printed_sensor_sweep(n_points: int = 31) -> FrequencySweep:
    """The printed 35 °C model as a measured sweep over 10–100 Hz (µA per mm, 0.5 dB / 5° per line)."""
    f = np.logspace(math.log10(SENSOR_BAND_HZ[0]), math.log10(SENSOR_BAND_HZ[1]), int(n_points))
    n = f.size
    return FrequencySweep(np.full(n, SENSOR_T_CAL_C), f, printed_sensor_response(f),
                          np.full(n, PRINTED_STD_DB), np.full(n, PRINTED_STD_DEG),
                          "tip_displacement", "mm", "current", "uA",
                          {"source": "seed 000 Sec. IV-A printed 35 C model, evaluated as data"})


def sensor_base():
    """Start of the sensor calibration: the seed 000 geometry with development values, T_ref = 35 °C."""
    return get_parameter_set("seed000_sensor_dev", T_ref=SENSOR_T_CAL_C + 273.15)


def calibrate_seed000_sensor(*, starts: int = 4, seed: int = 0, progress=None):
    """Calibrate the sensor physics to the printed 35 °C model (10–100 Hz); a CalibrationResult."""
    from ..estimation.calibration import calibrate
    from ..estimation.lsq import FreeParameter

    base = sensor_base()
    # start at the development values, a0 with the sign the phase calls for (module doc)
    free = [FreeParameter(n, lo, hi, "log", -abs(base.a0) if n == "a0" else None) for n, lo, hi in SENSOR_FREE]
    return calibrate(printed_sensor_sweep(), base, free, kind="sensor", starts=starts, seed=seed,
                     name="seed000_sensor", progress=progress, hold_undetermined="always")


@dataclass(frozen=True)
class Misfit:
    """Model minus data over a band: log-magnitude [dB] and phase [deg] (wrapped to ±180°)."""

    rms_db: float
    max_db: float
    rms_deg: float
    max_deg: float
    band_hz: tuple


def misfit(model_response, data_response, frequency_hz) -> Misfit:
    """RMS and max |error| of ``model_response`` against ``data_response`` (same lines)."""
    ratio = np.asarray(model_response, complex) / np.asarray(data_response, complex)
    db = 20 * np.log10(np.abs(ratio))
    deg = np.degrees(np.angle(ratio))
    f = np.asarray(frequency_hz, float)
    return Misfit(float(np.sqrt(np.mean(db**2))), float(np.max(np.abs(db))),
                  float(np.sqrt(np.mean(deg**2))), float(np.max(np.abs(deg))), (float(f.min()), float(f.max())))


def sensor_misfit_35c(params, n_points: int = 91) -> Misfit:
    """Misfit of a sensor parameter set against the printed 35 °C model over 10–100 Hz."""
    f = np.logspace(1, 2, n_points)
    S = SensorModel(params).frequency_response(f, [SENSOR_T_CAL_C])["S"][0, 0] * 1e3   # A/m → µA/mm
    return misfit(S, printed_sensor_response(f), f)


# ============================================================================ sensor: trends
@dataclass(frozen=True)
class SensorTrends:
    """High-pass view of the sensor over 10–100 Hz at each temperature.

    ``hf_gain_db``: |I/w| at 100 Hz [dB µA/mm]; ``cutoff_hz``: lowest frequency where the
    magnitude is within 3 dB of its in-band maximum [Hz]; ``phase_lag_deg``: band-mean of
    −phase (unwrapped) [deg].
    """

    temperature_c: tuple
    hf_gain_db: tuple
    cutoff_hz: tuple
    phase_lag_deg: tuple

    def monotone(self) -> dict:
        """Which published directions hold strictly at every step of rising temperature."""
        d = lambda v: np.diff(np.asarray(v))
        return {"cutoff_decreases": bool(np.all(d(self.cutoff_hz) < 0)),
                "hf_gain_decreases": bool(np.all(d(self.hf_gain_db) < 0)),
                "phase_lag_increases": bool(np.all(d(self.phase_lag_deg) > 0))}


def sensor_trends(params, temperatures_c=SENSOR_FIT_TEMPERATURES_C, n_points: int = 401) -> SensorTrends:
    """:class:`SensorTrends` of one parameter set (one vectorised model call)."""
    f = np.logspace(1, 2, n_points)
    r = SensorModel(params).frequency_response(f, list(temperatures_c))
    m = r.magnitude_db("S", 1e3)[0]
    ph = r.phase_deg("S")[0]
    top = m.max(axis=1, keepdims=True)
    first = np.argmax(m >= top - 3.0, axis=1)          # first index within 3 dB of the maximum
    # interpolate the crossing in log f between the neighbouring grid points
    cut = []
    for j, k in enumerate(first):
        if k == 0:
            cut.append(float(f[0]))
            continue
        y0, y1 = m[j, k - 1] - (top[j, 0] - 3.0), m[j, k] - (top[j, 0] - 3.0)
        lf = np.log10(f[k - 1]) + (np.log10(f[k]) - np.log10(f[k - 1])) * (-y0) / (y1 - y0)
        cut.append(float(10**lf))
    return SensorTrends(tuple(float(t) for t in temperatures_c), tuple(m[:, -1].tolist()), tuple(cut),
                        tuple((-ph.mean(axis=1)).tolist()))


#: The published directions the sensor laws are chosen on (the third, ``phase_lag_increases``, is not used;
#: on the grid it holds exactly when ``cutoff_decreases`` does).
SENSOR_CALIBRATION_TRENDS = ("cutoff_decreases", "hf_gain_decreases")
#: Grids searched by :func:`choose_sensor_laws` [1/K]; defaults first.
C_SLOPES = (0.0, -0.005, -0.01, -0.015, -0.02, -0.025, -0.03, -0.035, -0.04)
E_SLOPES = (-0.0075, -0.01, -0.0125, -0.015, -0.0175, -0.02)


def with_slopes(params, c_slope: float, e_slope: float):
    """``params`` with log-linear laws for C⁻ and E of the given slopes [1/K]."""
    return params.replace(laws=params.laws.with_(C_minus=LogLinear(slope=c_slope), E=LogLinear(slope=e_slope)))


def choose_sensor_laws(params, trends=SENSOR_CALIBRATION_TRENDS) -> tuple[float, float, SensorTrends]:
    """Smallest departure |c_slope| + |e_slope + 0.0075| on the grid making the named ``trends`` hold.

    Only the directions in ``trends`` (keys of :meth:`SensorTrends.monotone`) are used; the others
    in the returned :class:`SensorTrends` were not used (not necessarily independent of them).
    """
    unknown = set(trends) - {"cutoff_decreases", "hf_gain_decreases", "phase_lag_increases"}
    if unknown or not trends:
        raise IPMCError(f"choose_sensor_laws: trends must name some of cutoff_decreases, hf_gain_decreases, "
                        f"phase_lag_increases; got {sorted(trends)}")
    cands = sorted(((c, e) for c in C_SLOPES for e in E_SLOPES), key=lambda ce: (abs(ce[0]) + abs(ce[1] + 0.0075), ce))
    for c, e in cands:
        tr = sensor_trends(with_slopes(params, c, e))
        if all(tr.monotone()[k] for k in trends):
            return c, e, tr
    raise IPMCError(f"no (C- slope, E slope) on the grid makes {sorted(trends)} hold for seed 000")


# ============================================================================ actuator
@dataclass(frozen=True)
class ActuatorTrends:
    """19 °C vs 55 °C and the resonance of |M| at each temperature.

    ``max_difference_db``: the largest |D|, D = |M(19)| − |M(55)| [dB] on seed 001's grid (signed);
    ``at_hz``: where it occurs; ``resonance_hz``: peak of |M| per temperature (fine grid, 0.1–9 Hz).
    """

    max_difference_db: float
    at_hz: float
    resonance_hz: tuple
    temperature_c: tuple


def actuator_trends(params, temperatures_c=ACTUATOR_TEMPERATURES_C) -> ActuatorTrends:
    f = seed001_frequencies_hz()
    ff = np.logspace(-1.0, math.log10(9.0), 1500)
    model = ActuatorModel(params)
    m = model.frequency_response(f, [19.0, 55.0], quantities=("M",)).magnitude_db("M", 1e3)[0]
    D = m[0] - m[1]
    i = int(np.argmax(np.abs(D)))
    mf = np.abs(model.frequency_response(ff, list(temperatures_c), quantities=("M",))["M"][0])
    return ActuatorTrends(float(D[i]), float(f[i]), tuple(ff[np.argmax(mf, axis=1)].tolist()),
                          tuple(float(t) for t in temperatures_c))


def actuator_base():
    return get_parameter_set("seed001_actuator_dev")


def _actuator_with(base, x):
    E, c_slope = 1e8 * math.exp(x[0]), float(x[1])
    return base.replace(E=E, laws=base.laws.with_(C_minus=LogLinear(slope=c_slope)))


def solve_actuator_trend(base=None):
    """Solve D(3 Hz) = 7 dB, dD/dln f (3 Hz) = 0 for (E at T_ref, C⁻ slope); returns (params, solution)."""
    from scipy.optimize import least_squares

    base = base or actuator_base()
    f0 = ACTUATOR_TARGET_HZ * np.array([1 / 1.02, 1.0, 1.02])

    def res(x):
        m = ActuatorModel(_actuator_with(base, x)).frequency_response(f0, [19.0, 55.0], quantities=("M",))
        db = m.magnitude_db("M", 1e3)[0]
        D = db[0] - db[1]
        return [D[1] - ACTUATOR_TARGET_DB, (D[2] - D[0]) / math.log(1.02**2)]

    sol = least_squares(res, [math.log(4.5), -0.01], x_scale=[0.3, 0.01], xtol=1e-12, ftol=1e-12)
    if not sol.success or np.max(np.abs(sol.fun)) > 1e-6:
        raise IPMCError(f"the seed 001 trend equations were not solved: {sol.message}, residuals {sol.fun}")
    return _actuator_with(base, sol.x), sol


# ============================================================================ driver
def derive(progress=None) -> dict:
    """Run both derivations; returns the numbers stored in physmodel.parameter_sets and the records."""
    cal = calibrate_seed000_sensor(progress=progress)
    sensor = cal.parameters
    c, e, tr = choose_sensor_laws(sensor)
    act, sol = solve_actuator_trend()
    return {"sensor_calibration": cal, "sensor_values": {k: getattr(sensor, k) for k, *_ in SENSOR_FREE},
            "sensor_c_slope": c, "sensor_e_slope": e, "sensor_trends": tr,
            "sensor_misfit": sensor_misfit_35c(sensor),
            "actuator_E": act.E, "actuator_c_slope": act.laws.C_minus.slope,
            "actuator_trends": actuator_trends(act), "actuator_solution": sol}


def main() -> int:  # pragma: no cover - a derivation script
    out = derive()
    print(out["sensor_calibration"].summary())
    print("sensor values (store in parameter_sets.py):", {k: float(f"{v:.6g}") for k, v in out["sensor_values"].items()})
    print("sensor laws: C_minus slope", out["sensor_c_slope"], "E slope", out["sensor_e_slope"])
    print("sensor trends (chosen on", SENSOR_CALIBRATION_TRENDS, "):", out["sensor_trends"])
    print("unused phase-lag direction holds:", out["sensor_trends"].monotone()["phase_lag_increases"])
    print("35 C misfit:", out["sensor_misfit"])
    print(f"actuator: E = {out['actuator_E']:.6g} Pa, C_minus slope = {out['actuator_c_slope']:.6g} /K")
    print("actuator trends:", out["actuator_trends"])
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
