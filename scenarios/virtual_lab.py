"""A virtual laboratory: time-domain experiments on the physics, measured like a DAQ, reduced to a
frequency sweep with per-line σ by the same estimators a real record goes through.

    excitation design (multisine or stepped sine, :mod:`physmodel.data.excitation`)
      → physics plant at each bath temperature (:func:`physmodel.data.timesim.simulate`: the exact
        transfer function through a verified rational realisation, first-order-hold input)
      → optional seed 000 transimpedance chain (sensor current → amplifier volts)
      → measurement: white Gaussian noise on the recorded input and output, then the ADC's
        quantisation (rounding to ``adc_step``)
      → :class:`~physmodel.data.timerecord.TimeRecord` per temperature (display units: V, mm, µA)
      → FRF with per-line σ (:func:`~physmodel.estimation.frf.h1` on whole periods of a multisine,
        or :func:`~physmodel.estimation.stepped.stepped_sine`)
      → one :class:`~physmodel.data.sweep.FrequencySweep` over all temperatures, in the units of
        :data:`physmodel.data.units.QUANTITY_UNITS` (M in mm/V, S in µA/mm), ready for
        :func:`physmodel.estimation.calibration.calibrate` and :func:`surrogate.fit_sweep`.

Two known instrument factors are divided out of the estimate, each exactly:

* the chain's transimpedance ``TransimpedanceChain.response(jω)`` [V/A] (a calibrated instrument);
* the simulation's hold: a first-order-hold (linearly interpolated) input seen through its samples
  carries the factor ``sinc²(f/fs)`` (the triangle kernel's transform); a real record of a
  continuous input does not, so ``hold_correction=True`` (default) removes it; timesim runs the
  chain's amplifier pole on the current's samples, again through a first-order hold, and that
  discrete response is divided out exactly (:func:`chain_as_simulated`).  What stays is the
  aliasing of the hold's images, ``Σ_{n≠0} P(f − n fs) sinc²(f/fs − n) / P(f)``, made small by
  simulating on a grid ``oversample`` times finer than the DAQ's (see :func:`simulate_records`;
  ``tests/scenarios/test_virtual_lab.py`` checks it against the physics).

The per-line σ of a multisine line is an estimate with ν = 2(P − 1) degrees of freedom for P
measured periods (Student t; :mod:`physmodel.estimation.frf`); a calibration that weights by it as
if it were known states intervals about sqrt(ν/(ν − 2)) too narrow — measure more periods when the
intervals matter.

Not in σ (stated, measured in ``tests/benchmarks/bench_virtual_lab.py``): the realisation error
(≤ ``tol``, default 1e-4 relative), the transient left after ``transient_periods`` (choose them
with :func:`physmodel.data.excitation.settle_time_s`) and the H1 bias from noise on the recorded
input, ``1/(1 + N_uu/S_uu)`` per line.

Cost: one realisation (vector fit, ~0.02 s) and one simulation (one ``lfilter`` pass per modal
state over ``oversample × fs × duration`` samples) per temperature — timesim realises one
temperature at a time, so the temperatures are a Python loop of whole-record operations; the noise
of all temperatures is drawn in one call and the estimation is one call per temperature.  Measured
(``tests/benchmarks/bench_virtual_lab.py``): 8 temperatures × 100 s records at 500 Hz, oversampled
×8 (400 k samples each), 1.5-2.2 s wall, of which the simulation is ~90 %.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from physmodel.data.excitation import Multisine, SteppedSinePlan
from physmodel.data.sweep import FrequencySweep, merge_sweeps
from physmodel.data.timerecord import TimeRecord
from physmodel.data.units import QUANTITY_UNITS, UNITS, unit_scale
from physmodel.errors import IPMCError
from physmodel.sensor import TransimpedanceChain


# ---------------------------------------------------------------------------- configuration
@dataclass(frozen=True)
class Measurement:
    """How the virtual DAQ records the experiment.

    Attributes
    ----------
    output_noise_rms : float   white Gaussian noise on the recorded output, in SI of that signal:
        [m] for an actuator's tip displacement (laser), [A] for a sensor's current, [V] for the
        amplifier output when ``chain`` is given.
    input_noise_rms : float    white Gaussian noise on the recorded input: [V] (actuator) or [m] (sensor).
    output_adc_step, input_adc_step : float   quantisation step of the ADC channel, in SI of the
        recorded signal (e.g. 20 V / 2¹⁶ = 3.05e-4 V for a 16-bit ±10 V input); 0 = no quantisation.
    chain : TransimpedanceChain or None   sensors only: the seed 000 amplifier between the
        short-circuit current and the recorded voltage (its response is divided out of the estimate).
    seed : int, sequence of int or None   noise seed (``np.random.default_rng``'s: an integer ≥ 0, or
        a list of them, numpy ``SeedSequence`` entropy — the [next_measurement] step gives its
        recommended records ``[next_noise_seed, k, 0, 0, 0]``); required when there is noise.
    """

    output_noise_rms: float = 0.0
    input_noise_rms: float = 0.0
    output_adc_step: float = 0.0
    input_adc_step: float = 0.0
    chain: TransimpedanceChain | None = None
    seed: int | Sequence[int] | None = None

    def __post_init__(self):
        for k in ("output_noise_rms", "input_noise_rms", "output_adc_step", "input_adc_step"):
            v = getattr(self, k)
            if not (isinstance(v, (int, float, np.floating)) and math.isfinite(v) and v >= 0):
                raise IPMCError(f"Measurement.{k}={v!r} must be a finite number >= 0 (SI units)")
        if (self.output_noise_rms or self.input_noise_rms) and self.seed is None:
            raise IPMCError("Measurement.seed: a noisy measurement needs an explicit seed, an integer >= 0 or a list "
                            "of them (reproducibility)")
        words = [self.seed] if isinstance(self.seed, (int, np.integer)) else self.seed
        if self.seed is not None and not (isinstance(words, Sequence) and len(words) > 0 and all(
                isinstance(w, (int, np.integer)) and not isinstance(w, bool) and w >= 0 for w in words)):
            raise IPMCError(f"Measurement.seed={self.seed!r}: expected an integer >= 0 or a non-empty list of them "
                            "(numpy SeedSequence entropy)")
        if self.chain is not None and not hasattr(self.chain, "response"):
            raise IPMCError(f"Measurement.chain={self.chain!r} must be a physmodel.TransimpedanceChain or None")

    def describe(self) -> dict:
        d = {k: f"{getattr(self, k):g}" for k in ("output_noise_rms", "input_noise_rms", "output_adc_step",
                                                   "input_adc_step")}
        d["seed"] = str(self.seed)
        if self.chain is not None:
            c = self.chain
            d["chain"] = f"R1={c.R1:g} R2={c.R2:g} R3={c.R3:g} bandwidth_hz={c.bandwidth_hz}"
        return d


@dataclass(frozen=True)
class VirtualLabResult:
    """What :func:`virtual_lab` measured.

    Attributes
    ----------
    sweep : FrequencySweep      all temperatures, QUANTITY_UNITS display units, per-line σ
    estimates : tuple           ``(temperature_c, FRFEstimate)`` per temperature, in the record's
        units, before the chain and hold corrections
    records : tuple             one metadata dict per record (temperature, realisation, noise, ...)
    time_records : tuple        the :class:`TimeRecord` objects (only with ``keep_records=True``)
    timings_s : dict            wall time of each stage, summed over temperatures. [s]
    duration_s : float          measurement time of one record (what a laboratory would spend per
        temperature). [s]
    """

    sweep: FrequencySweep
    estimates: tuple
    records: tuple
    time_records: tuple = ()
    timings_s: dict = field(default_factory=dict)
    duration_s: float = 0.0


# ---------------------------------------------------------------------------- pieces
def _kind(model) -> str:
    kind = getattr(model, "kind", None)
    if kind in ("actuator", "sensor"):
        return kind
    raise IPMCError(f"model must be a physics model (kind 'actuator' or 'sensor'), got {type(model).__name__}")


def _drive(excitation, periods: int | None, transient_periods: int | None, oversample: int = 1) -> TimeRecord:
    """The signal file of a design (its header carries the design), sampled ``oversample`` times
    faster than the design's rate (the same band-limited waveform on a finer grid)."""
    from dataclasses import replace

    if oversample != 1:
        if isinstance(excitation, Multisine):
            excitation = replace(excitation, fs_hz=excitation.fs_hz * oversample,
                                 n_samples=excitation.n_samples * oversample)
        elif isinstance(excitation, SteppedSinePlan):
            excitation = replace(excitation, fs_hz=excitation.fs_hz * oversample)
    if isinstance(excitation, Multisine):
        if periods is None:
            raise IPMCError("periods: a multisine needs the number of measured periods (>= 2 for σ)")
        if periods < 2:
            raise IPMCError(f"periods={periods!r}: σ from the scatter between periods needs at least 2")
        return excitation.record(periods, 1 if transient_periods is None else transient_periods)
    if isinstance(excitation, SteppedSinePlan):
        if periods is not None or transient_periods is not None:
            raise IPMCError("periods/transient_periods: a stepped-sine plan carries its own periods and settle time")
        return excitation.record()
    raise IPMCError(f"excitation must be a Multisine or a SteppedSinePlan (physmodel.data.excitation), "
                    f"got {type(excitation).__name__}")


def _temperatures(temperatures_c) -> np.ndarray:
    T = np.atleast_1d(np.asarray(temperatures_c, dtype=float))
    if T.ndim != 1 or T.size == 0 or not np.all(np.isfinite(T)):
        raise IPMCError(f"temperatures_c must be a non-empty list of finite values [°C], got {temperatures_c!r}")
    if np.unique(T).size != T.size:
        raise IPMCError(f"temperatures_c repeats a value: {T.tolist()}; give each temperature once")
    return T


def _quantise(x: np.ndarray, step: float) -> np.ndarray:
    return np.round(x / step) * step if step > 0 else x


def chain_as_simulated(chain, frequency_hz, fsim_hz: float) -> np.ndarray:
    """The transimpedance chain [V/A] as :func:`physmodel.data.timesim.simulate` applies it: its
    amplifier pole run on the current's samples at ``fsim_hz`` [Hz] through a first-order hold
    (x[k+1] = e·x[k] + b0·u[k] + b1·u[k+1], exact for a linearly interpolated input), so at
    z = exp(j2πf/fsim) the response is ``r (b1 + b0/z) / (1 − e/z)``; the continuous pole's
    ``C(jω)`` times sinc²(f/fsim) only when the pole lies well below ``fsim``."""
    f = np.asarray(frequency_hz, dtype=float)
    if chain.bandwidth_hz is None:
        return np.full(f.shape, complex(chain.gain))
    a, h = -2 * np.pi * chain.bandwidth_hz, 1.0 / float(fsim_hz)
    ah = a * h
    e = math.exp(ah)
    i0 = (e - 1) / a
    i1 = (e - 1 - ah) / (a * ah)
    zi = np.exp(-2j * np.pi * f * h)
    return chain.gain * -a * ((i0 - i1) * zi + i1) / (1 - e * zi)


def simulate_records(model, excitation, temperatures_c, measurement: Measurement = Measurement(), *,
                     periods: int | None = None, transient_periods: int | None = None, oversample: int = 16,
                     set_index: int = 0, tol: float = 1e-4, timings: dict | None = None) -> list[TimeRecord]:
    """Time records of the physics driven by ``excitation`` at each temperature (see module doc).

    Parameters
    ----------
    model : ActuatorModel or SensorModel
    excitation : Multisine or SteppedSinePlan     its ``unit`` must be a voltage (actuator) or a
        length (sensor); the drive is converted to SI for the physics.
    temperatures_c : sequence of float    bath temperatures. [°C]
    measurement : Measurement
    periods, transient_periods : int      multisine only: measured and leading (discarded) periods
    oversample : int    the physics is simulated at ``oversample × fs`` with the design's waveform
        evaluated exactly on the finer grid, and the DAQ keeps every ``oversample``-th sample (an
        ideal reconstruction filter on the drive).  Simulating at ``fs`` itself feeds the plant the
        linear interpolation of the samples, whose images near multiples of ``fs`` alias back into
        the band weighted by the plant's response there: for the seed 000 sensor (S rises ~30× from
        40 Hz to 1 kHz) at fs = 1 kHz the error at 40 Hz is 4.6 % unoversampled, 5.2e-3 with 4,
        1.6e-3 with 8, 4.5e-4 with the default 16 and 1.2e-4 with 32 (about oversample^-1.8);
        the seed 001 actuator's response falls with frequency and needs none (its error is the
        realisation's, < 1e-4).  The simulation's cost grows in proportion.
    set_index : int                       parameter set of the model to simulate
    tol : float                           realisation accuracy (max relative error)

    Returns
    -------
    list of TimeRecord, one per temperature: channels input (``voltage`` [V] or
    ``tip_displacement`` [mm]) and output (``tip_displacement`` [mm], ``current`` [uA] or
    ``amplifier_output`` [V]); metadata ``temperature_c``, the design header, the realisation and
    the measurement model.
    """
    from physmodel.data.timesim import model_realization, simulate

    kind = _kind(model)
    T = _temperatures(temperatures_c)
    if not (isinstance(oversample, (int, np.integer)) and 1 <= oversample <= 1024):
        raise IPMCError(f"oversample={oversample!r} must be a whole number from 1 to 1024")
    sig = _drive(excitation, periods, transient_periods)
    fine = _drive(excitation, periods, transient_periods, int(oversample)) if oversample > 1 else sig
    if measurement.chain is not None and kind != "sensor":
        raise IPMCError("Measurement.chain: a transimpedance chain reads a sensor's current; the model is an actuator")
    (in_name, in_unit), = sig.units.items()
    want = "voltage" if kind == "actuator" else "length"
    if UNITS.get(in_unit, ("?",))[0] != want:
        raise IPMCError(f"excitation unit {in_unit!r}: a{'n' if kind == 'actuator' else ''} {kind} is driven by a "
                        f"{want} (e.g. {'V' if kind == 'actuator' else 'mm'})")
    R = int(oversample)
    u_fine = fine.channels[in_name] * unit_scale(in_unit)
    u_si = u_fine[::R]
    t = sig.t
    if u_si.size != t.size:                 # the fine grid holds the coarse one exactly
        raise IPMCError(f"oversample={R}: the design's {t.size} samples do not divide its fine grid")
    fs = float(excitation.fs_hz)
    if kind == "actuator":
        (i_name, i_unit), (o_name, o_unit) = ("voltage", "V"), ("tip_displacement", "mm")
    else:
        i_name, i_unit = "tip_displacement", "mm"
        o_name, o_unit = ("amplifier_output", "V") if measurement.chain is not None else ("current", "uA")
    n_T, n = T.size, t.size
    tm = timings if timings is not None else {}
    rng = np.random.default_rng(measurement.seed)
    t0 = time.perf_counter()
    e_out = measurement.output_noise_rms * rng.standard_normal((n_T, n)) if measurement.output_noise_rms else None
    e_in = measurement.input_noise_rms * rng.standard_normal((n_T, n)) if measurement.input_noise_rms else None
    tm["noise"] = tm.get("noise", 0.0) + time.perf_counter() - t0
    recs = []
    for k, Tk in enumerate(T):
        t0 = time.perf_counter()
        # realised over the design's band (to 20·fs, timesim's rule for fs): it holds the first
        # images of the fine grid's hold for oversample <= 20 at a vector fit's cost at fs
        real = model_realization(model, float(Tk), fs, float(t[-1] - t[0]), set_index=set_index, tol=tol)
        t1 = time.perf_counter()
        ts = simulate(model, float(Tk), fine.t, u_fine, chain=measurement.chain, set_index=set_index,
                      realization=real)
        t2 = time.perf_counter()
        y = ts.output[::R] if e_out is None else ts.output[::R] + e_out[k]
        u = u_si if e_in is None else u_si + e_in[k]
        y = _quantise(y, measurement.output_adc_step)
        u = _quantise(u, measurement.input_adc_step)
        meta = {"temperature_c": f"{Tk:g}", **{k2: v for k2, v in sig.metadata.items()},
                "virtual_lab": "scenarios.virtual_lab", "model": ts.metadata["model"],
                "parameter_set": ts.metadata["parameter_set"], "realization": ts.metadata["realization"],
                "hold": ts.metadata["hold"], "simulation_fs_hz": f"{fs * R:.17g}", "oversample": str(R),
                **measurement.describe()}
        recs.append(TimeRecord(t, {i_name: u / unit_scale(i_unit), o_name: y / unit_scale(o_unit)},
                               {i_name: i_unit, o_name: o_unit}, meta))
        tm["realization"] = tm.get("realization", 0.0) + t1 - t0
        tm["simulation"] = tm.get("simulation", 0.0) + t2 - t1 + time.perf_counter() - t2
    return recs


def estimate(record: TimeRecord, excitation, *, transient_periods: int | None = None, estimator: str = "h1"):
    """The FRF of a virtual-lab (or laboratory) record of ``excitation`` — the estimator its design
    calls for: H1/H2 on whole multisine periods (boxcar, no overlap, the transient periods discarded,
    only the excited lines), or the stepped-sine fit of the plan."""
    from physmodel.estimation.frf import estimate_record

    names = list(record.channels)
    if len(names) != 2:
        raise IPMCError(f"record: expected an input and an output channel, got {names}")
    if isinstance(excitation, Multisine):
        tp = 1 if transient_periods is None else transient_periods
        return estimate_record(record, names[0], [names[1]], method=estimator, nperseg=excitation.n_samples,
                               noverlap=0, window="boxcar", discard_s=tp * excitation.period_s,
                               frequencies_hz=excitation.frequency_hz)
    if isinstance(excitation, SteppedSinePlan):
        return estimate_record(record, names[0], [names[1]], method="stepped_sine", plan=excitation)
    raise IPMCError(f"excitation must be a Multisine or a SteppedSinePlan, got {type(excitation).__name__}")


def virtual_lab(model, excitation, temperatures_c: Sequence[float], measurement: Measurement = Measurement(), *,
                periods: int | None = None, transient_periods: int | None = None, estimator: str = "h1",
                hold_correction: bool = True, max_std_db: float | None = None, oversample: int = 16,
                set_index: int = 0, tol: float = 1e-4, keep_records: bool = False) -> VirtualLabResult:
    """Simulate, measure and estimate: a :class:`FrequencySweep` of the model's main quantity
    (actuator M in mm/V, sensor S in µA/mm) with per-line σ, over all ``temperatures_c`` [°C].

    ``estimator``: "h1" or "h2" for a multisine (ignored for a stepped sine); ``max_std_db`` drops
    lines whose σ of the magnitude exceeds it [dB] (the first-order σ is not Gaussian beyond about
    1 dB, see :mod:`physmodel.estimation.frf`).  Other arguments: :func:`simulate_records`.
    """
    from physmodel.estimation.frf import FRFEstimate  # noqa: F401  (documented type)

    if estimator not in ("h1", "h2"):
        raise IPMCError(f"estimator={estimator!r}; expected 'h1' or 'h2'")
    kind = _kind(model)
    timings: dict = {}
    recs = simulate_records(model, excitation, temperatures_c, measurement, periods=periods,
                            transient_periods=transient_periods, oversample=oversample, set_index=set_index, tol=tol,
                            timings=timings)
    q = "M" if kind == "actuator" else "S"
    _, unit_in, _, unit_out = QUANTITY_UNITS[(kind, q)]
    fs = float(excitation.fs_hz)
    sweeps, ests = [], []
    t0 = time.perf_counter()
    for rec in recs:
        Tk = rec.temperature_c()
        e = estimate(rec, excitation, transient_periods=transient_periods, estimator=estimator)
        ests.append((Tk, e))
        factor = np.ones(e.frequency_hz.size, dtype=complex)
        notes = {}
        foh = hold_correction and rec.metadata.get("hold") == "foh"
        fsim = float(rec.metadata.get("simulation_fs_hz", fs))
        if measurement.chain is not None:
            c = measurement.chain
            if foh and c.bandwidth_hz is not None:
                factor *= chain_as_simulated(c, e.frequency_hz, fsim)
                notes["chain_divided_out"] = f"as simulated: its pole discretised with a first-order hold at {fsim:g} Hz"
            else:
                factor *= c.response(2j * np.pi * e.frequency_hz)
                notes["chain_divided_out"] = "yes"
        if foh:
            factor *= np.sinc(e.frequency_hz / fsim) ** 2
            notes["hold_correction"] = f"divided by sinc^2(f/{fsim:g} Hz) of the simulation's first-order hold"
        out_unit = e.output_units[0]
        if measurement.chain is not None:      # V → A through the chain's V/A
            out_unit = "A"
        from dataclasses import replace

        e2 = replace(e, response=e.response / factor, output_names=("current",) if measurement.chain is not None
                     else e.output_names, output_units=(out_unit,))
        sw = e2.to_sweep(Tk, max_std_db=max_std_db, quantity=q,
                         metadata={"source": "scenarios.virtual_lab", "parameter_set": rec.metadata["parameter_set"],
                                   "model": rec.metadata["model"], "excitation": rec.metadata.get("excitation", ""),
                                   **measurement.describe(), **notes})
        sweeps.append(sw.in_units(unit_in, unit_out))
    timings["estimation"] = time.perf_counter() - t0
    return VirtualLabResult(merge_sweeps(sweeps), tuple(ests), tuple(r.metadata for r in recs),
                            tuple(recs) if keep_records else (), timings, float(recs[0].t[-1] - recs[0].t[0] + 1 / fs))




# ---------------------------------------------------------------------------- scenario tables
#: Keys of a scenario's ``[sweep]`` table read when ``source = "virtual_lab"`` (with defaults).
SWEEP_KEYS = {"source": "virtual_lab", "temperatures_c": None, "fmin_hz": 0.1, "fmax_hz": 100.0, "points": 40,
              "excitation": "multisine", "fs_hz": None, "period_s": None, "periods": 8, "transient_periods": 2,
              "rms": 1.0, "amplitude": 1.0, "phases": "schroeder", "settle_s": 0.0, "settle_periods": 0.0,
              "min_measure_s": 0.0, "oversample": 16, "estimator": "h1", "max_std_db": None,
              "held_out_c": None, "plot_temperatures_c": None}
#: Keys of the ``[noise]`` table for a virtual lab (SI units; ``kind = "time"``).
NOISE_KEYS = {"kind": "time", "output_noise_rms": 0.0, "input_noise_rms": 0.0, "output_adc_step": 0.0,
              "input_adc_step": 0.0, "chain": None, "chain_bandwidth_hz": None, "seed": None}


def from_config(model, sweep: dict, noise: dict | None = None, where: str = "") -> VirtualLabResult:
    """Run the virtual lab described by a scenario's ``[sweep]`` and ``[noise]`` tables.

    ``[sweep]``: ``temperatures_c`` (required), ``fmin_hz``, ``fmax_hz``, ``points`` (log-spaced
    lines), ``excitation`` = "multisine" (``fs_hz``, ``period_s``, ``periods``,
    ``transient_periods``, ``rms``, ``phases``) or "stepped" (``fs_hz``, ``amplitude``, ``periods``,
    ``settle_s``, ``settle_periods``, ``min_measure_s``), ``oversample``, ``estimator``,
    ``max_std_db``; amplitudes in V (actuator) or mm (sensor).  ``[noise]``: ``kind = "time"``,
    ``output_noise_rms``, ``input_noise_rms``, ``output_adc_step``, ``input_adc_step`` (SI of the
    recorded signal), ``chain = [R1, R2, R3]`` [Ω] and ``chain_bandwidth_hz`` (sensor), ``seed``.
    Unknown keys and wrong types raise :class:`IPMCError` naming ``[table] key``.
    """
    from physmodel.data.excitation import multisine, stepped_sine_plan

    sweep, noise = dict(sweep), dict(noise or {})
    if sweep.get("source", "virtual_lab") != "virtual_lab":
        raise IPMCError(f"{where}[sweep] source = {sweep['source']!r}; this reader handles 'virtual_lab'")
    if noise.get("kind", "time") != "time":
        raise IPMCError(f"{where}[noise] kind = {noise['kind']!r}: a virtual lab adds noise to the time records; "
                        f"use kind = \"time\" with output_noise_rms, input_noise_rms, output_adc_step, ...")
    for table, got, known in (("sweep", sweep, SWEEP_KEYS), ("noise", noise, NOISE_KEYS)):
        bad = sorted(set(got) - set(known))
        if bad:
            raise IPMCError(f"{where}[{table}] {bad[0]}: not a virtual-lab key; expected one of {sorted(known)}")
    cfg = {**SWEEP_KEYS, **sweep}
    nz = {**NOISE_KEYS, **noise}
    kind = _kind(model)
    if cfg["temperatures_c"] is None:
        raise IPMCError(f"{where}[sweep] temperatures_c: required (a list of bath temperatures [°C])")
    if cfg["fs_hz"] is None:
        raise IPMCError(f"{where}[sweep] fs_hz: required (the DAQ's sample rate [Hz])")
    lo, hi, n = cfg["fmin_hz"], cfg["fmax_hz"], cfg["points"]
    if not (isinstance(n, int) and n >= 1 and 0 < lo <= hi):
        raise IPMCError(f"{where}[sweep] fmin_hz/fmax_hz/points: need 0 < fmin_hz <= fmax_hz and points >= 1, "
                        f"got {lo!r}, {hi!r}, {n!r}")
    ch, unit = ("voltage", "V") if kind == "actuator" else ("tip_displacement", "mm")
    chain = None
    if nz["chain"] is not None:
        r = nz["chain"]
        if not (isinstance(r, (list, tuple)) and len(r) == 3):
            raise IPMCError(f"{where}[noise] chain: expected [R1, R2, R3] in ohm, got {r!r}")
        chain = TransimpedanceChain(float(r[0]), float(r[1]), float(r[2]), bandwidth_hz=nz["chain_bandwidth_hz"])
    try:
        meas = Measurement(float(nz["output_noise_rms"]), float(nz["input_noise_rms"]), float(nz["output_adc_step"]),
                           float(nz["input_adc_step"]), chain, nz["seed"])
        exc: Multisine | SteppedSinePlan
        if cfg["excitation"] == "multisine":
            period = cfg["period_s"] if cfg["period_s"] is not None else max(10.0, 1.0 / lo)
            f = np.unique(np.maximum(np.round(np.geomspace(lo, hi, n) * period), 1)) / period
            exc = multisine(f, cfg["fs_hz"], period, rms=cfg["rms"], phases=cfg["phases"], channel=ch, unit=unit)
            kw = {"periods": cfg["periods"], "transient_periods": cfg["transient_periods"]}
        elif cfg["excitation"] == "stepped":
            exc = stepped_sine_plan(np.geomspace(lo, hi, n), cfg["fs_hz"], amplitude=cfg["amplitude"],
                                    periods=cfg["periods"], min_measure_s=cfg["min_measure_s"],
                                    settle_s=cfg["settle_s"], settle_periods=cfg["settle_periods"], channel=ch,
                                    unit=unit)
            kw = {}
        else:
            raise IPMCError(f"[sweep] excitation = {cfg['excitation']!r}; expected 'multisine' or 'stepped'")
        return virtual_lab(model, exc, cfg["temperatures_c"], meas, estimator=cfg["estimator"],
                           max_std_db=cfg["max_std_db"], oversample=cfg["oversample"], **kw)
    except IPMCError as exc_:
        raise IPMCError(f"{where}[sweep]/[noise] virtual lab: {exc_}") from None
    except (TypeError, ValueError) as exc_:
        raise IPMCError(f"{where}[sweep]/[noise] virtual lab: a value has the wrong type ({exc_})") from None


__all__ = [
    "NOISE_KEYS",
    "SWEEP_KEYS",
    "Measurement",
    "chain_as_simulated",
    "VirtualLabResult",
    "estimate",
    "from_config",
    "simulate_records",
    "virtual_lab",
]
