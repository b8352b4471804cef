"""A user's own strips and their laboratory records, written without the library (issue 24).

Everything the journey benchmark (``bench_journey.py``) treats as "the real strip" lives here: the
strip's true response M_true(f, T) [m/V], the multisine records a laboratory would take of it, the
dense sweep of its TRUE response (the "truth" route) and the time simulation that applies a voltage
to it.  On purpose this module imports neither ``physmodel`` nor ``surrogate``, ``inversion`` or
``scenarios``: the physics is :mod:`tests.discrepancy.independent_physics` (an independently written
Chen–Tan actuator with its own parametrisation of every effect), the excitation, the noise, the
quantisation, the file writers and the FFT simulation are written here.  The files follow the
formats the README documents ("Data formats", ``ipmc-timeseries`` and ``ipmc-sweep``), so the
library reads them as it would read a user's.

Strips (:data:`STRIPS`): each has its own geometry, its own material values away from the generic
development set the user starts from (``seed001_actuator_dev``), its own temperature laws (Arrhenius
diffusivity written as a Q10, a log-linear modulus slope, κe ∝ water permittivity, ionic leakage ∝
d/T) and ONE effect that the library's baseline lacks but can name:

* ``A`` (for tuning the harness): 25 × 6 mm, 0.28 mm thick; a sampling skew of 3 ms plus a
  zero-order-hold DAC at 1 kHz (the library's ``time_delay``; its delay ≈ skew + half the DAC
  period = 3.5 ms); measured at 15/25/35/45 °C, used at 30 °C.
* ``B`` (held out): 35 × 8 mm, 0.2 mm thick, other laws; an 8 Ω resistance in series with the
  strip (leads, clamp contact, amplifier output: the library's ``series_resistance``); measured at
  20/30/40/50 °C, used at 45 °C.

    strip = get_strip("A")
    M = true_response(strip, f_hz, T_c)                 # (n_T, n_f) complex [m/V]
    paths = write_lab_records(strip, "work/A", seed=1)  # one record per temperature + drive.csv
    y = apply_voltage(strip, 30.0, t, v)                # tip displacement [m] at 30 °C
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE.parent / "discrepancy"))

import independent_physics as ip  # noqa: E402

#: Cantilever first root (clamped-free), for the density equivalent of a first-mode frequency.
_LAM1 = float(ip.cantilever_roots(1)[0])


@dataclass(frozen=True)
class Strip:
    """One user's strip: independent-physics base parameters, one effect and the lab protocol.

    ``base``: keys of :func:`independent_physics.base_state` (SI; f1 [Hz], T0_c [°C]).
    ``effect``: ``{independent effect name: its parameters}`` (exactly one).
    ``library_effect``: the same effect in the library's names and parameters (for the report and
    for a reader who wants to compare with what ``ipmc diagnose`` names).
    ``temperatures_c``: the measured bath temperatures; ``target_c``: where the voltage is used.
    ``noise_m``: laser noise rms [m]; ``drive_rms_v``: multisine rms [V]; ``range_*``: ±ADC ranges.
    """

    name: str
    description: str
    base: dict
    effect: dict
    library_effect: dict
    temperatures_c: tuple
    target_c: float
    noise_m: float = 15e-6
    drive_rms_v: float = 1.0
    range_v: float = 10.0
    range_m: float = 5e-3
    fs_hz: float = 500.0
    period_s: float = 20.0
    f_lines_hz: tuple = (0.1, 10.0)
    n_lines: int = 25
    periods: int = 6
    dense_temperatures_c: tuple = ()
    extra: dict = field(default_factory=dict)


STRIPS: dict[str, Strip] = {
    "A": Strip(
        name="A",
        description="25 x 6 mm, 0.28 mm thick; time delay (3 ms sampling skew + 1 kHz zero-order-hold DAC)",
        base=dict(L=25e-3, W=6e-3, h=0.14e-3, d=3.2e-11, C=1000.0, eps=1.5e-6, alpha=-0.14, r1s=10.0, r2s=1e-5,
                  Gp=1 / 0.5, E=260e6, f1=7.0, zeta=0.12, T0_c=25.0, thermal=True, Q10_d=1.35,
                  E_logslope=-0.011, eps_water=True),
        effect={"time_delay": {"skew_s": 3e-3, "dac_period_s": 1e-3}},
        library_effect={"time_delay": {"delay": 3e-3 + 0.5e-3}},
        temperatures_c=(15.0, 25.0, 35.0, 45.0),
        target_c=30.0,
        noise_m=15e-6,
        dense_temperatures_c=(15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 45.0),
    ),
    "B": Strip(
        name="B",
        description="35 x 8 mm, 0.2 mm thick; 8 Ohm in series with the strip (leads, contact, amplifier output)",
        base=dict(L=35e-3, W=8e-3, h=0.1e-3, d=5e-11, C=1150.0, eps=1.1e-6, alpha=-0.06, r1s=10.0, r2s=1e-5,
                  Gp=1 / 0.5, E=220e6, f1=4.5, zeta=0.15, T0_c=25.0, thermal=True, Q10_d=1.22,
                  E_logslope=-0.006, eps_water=True),
        effect={"series_resistance": {"resistance": 8.0}},
        library_effect={"series_resistance": {"resistance": 8.0}},
        temperatures_c=(20.0, 30.0, 40.0, 50.0),
        target_c=45.0,
        noise_m=12e-6,
        dense_temperatures_c=(20.0, 25.0, 30.0, 35.0, 40.0, 45.0, 50.0),
    ),
}


def get_strip(name: str) -> Strip:
    if name not in STRIPS:
        raise ValueError(f"unknown strip {name!r}; expected one of {sorted(STRIPS)}")
    return STRIPS[name]


def geometry_params(strip: Strip) -> dict:
    """What the user knows of their strip and tells the CLI: length, width, HALF thickness [m]."""
    return {"L": strip.base["L"], "W": strip.base["W"], "h": strip.base["h"]}


def library_fields(strip: Strip) -> dict:
    """The strip's base in the library's parameter names (SI; laws as the library spells them).

    For the report only (the journey never hands the truth to the CLI).  The effective density
    ``rho`` is the one whose Euler–Bernoulli first mode is ``f1`` at T0."""
    b = strip.base
    w1 = 2 * math.pi * b["f1"]
    rho = b["E"] * b["h"] ** 2 / 3.0 * (_LAM1**2 / (b["L"] ** 2 * w1)) ** 2
    laws = {"d": {"law": "Arrhenius", "activation_energy": float(ip.ea_from_q10(b["Q10_d"], b["T0_c"]))},
            "E": {"law": "LogLinear", "slope": b["E_logslope"]},
            "kappa_e": {"law": "WaterPermittivity"}, "Rp_specific": {"law": "IonicResistance"}}
    return dict(L=b["L"], W=b["W"], h=b["h"], d=b["d"], C_minus=b["C"], kappa_e=b["eps"], alpha0=b["alpha"],
                r1_sheet=b["r1s"], r2_specific=b["r2s"], Rp_specific=1.0 / b["Gp"], E=b["E"], rho=rho,
                xi=b["zeta"], T_ref=b["T0_c"] + ip.T_ZERO, laws=laws, effects=strip.library_effect)


# --------------------------------------------------------------------------- true response
#: Frequency standing in for DC [Hz]: M(f) is flat to < 1e-12 relative below ~1e-6 Hz.
F_DC = 1e-9


def true_response(strip: Strip, frequency_hz, temperature_c) -> np.ndarray:
    """M_true [m/V], shape (n_T, n_f), effect included; f = 0 is evaluated at :data:`F_DC`."""
    f = np.atleast_1d(np.asarray(frequency_hz, dtype=float))
    f = np.where(f <= 0.0, F_DC, f)
    T = np.atleast_1d(np.asarray(temperature_c, dtype=float))
    return ip.actuator_response(strip.base, f, T, strip.effect)["M"]


# --------------------------------------------------------------------------- lab records
@dataclass(frozen=True)
class Drive:
    """One period of a multisine Σ A_k cos(2π k_k t/T_p + φ_k) on FFT lines ``lines`` of ``n`` samples."""

    fs_hz: float
    n: int
    lines: np.ndarray
    amplitudes: np.ndarray
    phases: np.ndarray

    @property
    def frequency_hz(self) -> np.ndarray:
        return self.lines * self.fs_hz / self.n

    def samples(self, n_periods: int) -> np.ndarray:
        k = np.arange(self.n * n_periods)
        arg = 2 * np.pi * np.outer(k, self.lines) / self.n + self.phases
        return np.cos(arg) @ self.amplitudes

    def header(self) -> dict:
        """The design in the ``multisine`` header that ``ipmc frf`` reads (README 'From time records')."""
        return {"fs_hz": self.fs_hz, "n_samples": int(self.n), "lines": [int(k) for k in self.lines],
                "amplitudes": [float(a) for a in self.amplitudes], "phases_rad": [float(p) for p in self.phases],
                "phase_method": "random", "channel": "voltage", "unit": "V"}


def design_drive(strip: Strip, rng: np.random.Generator) -> Drive:
    """Log-spaced lines over ``strip.f_lines_hz`` (distinct FFT lines of one period), random phases,
    equal amplitudes scaled to ``strip.drive_rms_v``; the draw with the lowest crest factor of 20."""
    n = int(round(strip.period_s * strip.fs_hz))
    lo, hi = (int(round(f * strip.period_s)) for f in strip.f_lines_hz)
    lines = np.unique(np.round(np.geomspace(lo, hi, strip.n_lines)).astype(int))
    amp = np.full(lines.size, strip.drive_rms_v * math.sqrt(2.0 / lines.size))
    best, best_cf = None, np.inf
    for _ in range(20):
        ph = rng.uniform(0, 2 * np.pi, lines.size)
        d = Drive(strip.fs_hz, n, lines, amp, ph)
        u = d.samples(1)
        cf = float(np.max(np.abs(u)) / np.sqrt(np.mean(u**2)))
        if cf < best_cf:
            best, best_cf = d, cf
    assert best is not None
    return best


def quantise(x, full_range: float, bits: int = 16) -> np.ndarray:
    """Mid-tread quantiser of a ±``full_range`` ADC with ``bits`` bits (clipped at the rails)."""
    lsb = 2.0 * full_range / 2**bits
    return np.clip(np.round(np.asarray(x) / lsb), -(2 ** (bits - 1)), 2 ** (bits - 1) - 1) * lsb


def _write_timeseries(path: Path, t, cols: dict, meta: dict) -> None:
    lines = ["# ipmc-timeseries 1"]
    for col in cols:
        name, unit = col.rsplit("_", 1)
        lines.append(f"# {col}: {name} [{unit}]")
    lines += [f"# {k}: {v}" for k, v in meta.items()]
    arr = np.column_stack([t] + list(cols.values()))
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines) + "\n")
        fh.write(",".join(["time_s"] + list(cols)) + "\n")
        np.savetxt(fh, arr, delimiter=",", fmt="%.9g")


def write_lab_records(strip: Strip, folder, seed: int = 1, quick: bool = False) -> dict:
    """Multisine records of the strip at each measured temperature, as a laboratory writes them.

    The drive is periodic from t = 0 (one transient period, then ``strip.periods`` measured ones;
    ``quick``: 3), the response is its EXACT steady state (M_true at the excited lines), laser noise
    (white, ``strip.noise_m`` rms) is added to the displacement and both channels are quantised by a
    16-bit ADC (±10 V, ±5 mm).  Writes ``record_<T>C.csv`` (``time_s, voltage_V,
    tip_displacement_mm``, ``temperature_c`` and ``multisine`` headers) and ``drive.csv`` (the
    signal file with the design, for ``ipmc frf --lines``).  Returns paths and the design."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    r_drive, r_noise = (np.random.default_rng(s) for s in np.random.SeedSequence([0x24, int(seed)]).spawn(2))
    drive = design_drive(strip, r_drive)
    n_per = 1 + (3 if quick else strip.periods)
    u1 = drive.samples(1)
    u = np.tile(u1, n_per)
    t = np.arange(u.size) / strip.fs_hz
    meta_ms = {"excitation": "multisine", "multisine": json.dumps(drive.header()), "transient_periods": 1,
               "periods": n_per - 1}
    _write_timeseries(folder / "drive.csv", t[: u1.size], {"voltage_V": u1}, meta_ms)
    M = true_response(strip, drive.frequency_hz, strip.temperatures_c)
    k = np.arange(drive.n)
    records = []
    for i, T in enumerate(strip.temperatures_c):
        H = M[i]
        y1 = np.cos(2 * np.pi * np.outer(k, drive.lines) / drive.n + drive.phases + np.angle(H)) @ (
            drive.amplitudes * np.abs(H))
        y = np.tile(y1, n_per) + strip.noise_m * r_noise.standard_normal(u.size)
        cols = {"voltage_V": quantise(u, strip.range_v), "tip_displacement_mm": quantise(y, strip.range_m) * 1e3}
        p = folder / f"record_{T:g}C.csv"
        meta = {"temperature_c": f"{T:g}", **meta_ms,
                "source": f"tests/benchmarks/journey_strip.py strip {strip.name}, seed {seed}"}
        _write_timeseries(p, t, cols, meta)
        records.append(p)
    return {"records": records, "drive": folder / "drive.csv", "design": drive,
            "frequency_hz": drive.frequency_hz, "M_lines": M}


# --------------------------------------------------------------------------- the truth route's sweep
def write_sweep_csv(path, temperatures_c, frequency_hz, response_mm_per_v, sigma_db: float = 0.0,
                    sigma_deg: float = 0.0, seed: int = 3, source: str = "") -> Path:
    """``response_mm_per_v`` (n_T, n_f) as an ``ipmc-sweep`` CSV (README 'Data formats'), with
    optional seeded magnitude/phase noise of std ``sigma_db`` / ``sigma_deg`` (then also stated in
    the std columns, as ``ipmc sweep --noise magphase`` does; without noise no std columns, as
    ``ipmc sweep`` writes a noise-free sweep)."""
    f = np.asarray(frequency_hz, dtype=float)
    T = np.asarray(temperatures_c, dtype=float)
    M = np.asarray(response_mm_per_v, dtype=complex).reshape(T.size, f.size)
    rng = np.random.default_rng(np.random.SeedSequence([0x24, 0x5EE9, int(seed)]))
    mag = 20 * np.log10(np.abs(M)) + sigma_db * rng.standard_normal(M.shape)
    ph = np.degrees(np.unwrap(np.angle(M), axis=1)) + sigma_deg * rng.standard_normal(M.shape)
    noisy = sigma_db > 0 or sigma_deg > 0
    rows = []
    for i, Ti in enumerate(T):
        for j, fj in enumerate(f):
            rows.append(f"{Ti:g},{fj:.10g},{mag[i, j]:.10g},{ph[i, j]:.10g}"
                        + (f",{max(sigma_db, 1e-3):g},{max(sigma_deg, 1e-3):g}" if noisy else ""))
    path = Path(path)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# ipmc-sweep 1\n# input: voltage [V]\n# output: tip_displacement [mm]\n")
        if source:
            fh.write(f"# source: {source}\n")
        fh.write("temperature_c,frequency_hz,magnitude_db,phase_deg"
                 + (",magnitude_std_db,phase_std_deg\n" if noisy else "\n"))
        fh.write("\n".join(rows) + "\n")
    return path


def write_true_sweep(strip: Strip, path, temperatures_c, fmin_hz: float, fmax_hz: float, points: int,
                     sigma_db: float = 0.0, sigma_deg: float = 0.0, seed: int = 3) -> Path:
    """The strip's TRUE response on ``points`` log-spaced lines as an ``ipmc-sweep`` CSV in mm/V."""
    f = np.geomspace(fmin_hz, fmax_hz, points)
    M = true_response(strip, f, temperatures_c) * 1e3
    return write_sweep_csv(path, temperatures_c, f, M, sigma_db, sigma_deg, seed,
                           f"true response of strip {strip.name} (tests/benchmarks/journey_strip.py)")


# --------------------------------------------------------------------------- applying a voltage
#: Settling time allowed for in the padding [s].  Generous: the impulse response of M_true (strips
#: A and B, 15-50 °C) has decayed to < 1e-5 of its peak after 5 s and < 1e-8 after 10 s (the
#: benchmark checks it: doubling the padding changes the response by ~1e-15 of the reference RMS).
TAU_SLOW_S = 30.0


def apply_voltage(strip: Strip, temperature_c: float, t, v, pad_factor: float = 1.0) -> np.ndarray:
    """Tip displacement [m] of the true strip at ``temperature_c`` driven by ``v`` [V] sampled at
    uniform times ``t`` [s] (at rest before ``t[0]``).

    Linear convolution by FFT: the record is zero-padded to ≥ ``pad_factor`` × (2 N + 4 τ_slow fs)
    samples (τ_slow = :data:`TAU_SLOW_S`), so the response that spills past the record end has
    decayed before it wraps around; M_true is evaluated on the FFT grid (DC at :data:`F_DC`), i.e.
    ``v`` is taken as samples of a band-limited signal.  No extra output hold is applied: at the
    benchmark's 10 kHz a zero-order hold would add a 50 µs delay (0.03 % of a 1 Hz sine); strip A's
    own chain (skew + its 1 kHz DAC) is part of M_true."""
    t = np.asarray(t, dtype=float)
    v = np.asarray(v, dtype=float)
    dt = (t[-1] - t[0]) / (t.size - 1)
    n_min = max(int(pad_factor * (2 * t.size + 4 * TAU_SLOW_S / dt)), 2 * t.size)
    n_fft = 1 << int(math.ceil(math.log2(n_min)))
    f = np.fft.rfftfreq(n_fft, dt)
    H = true_response(strip, f, [temperature_c])[0]
    y = np.fft.irfft(np.fft.rfft(v, n_fft) * H, n_fft)[: t.size]
    return y


def band_limited_reference(duration_s: float, fs_hz: float, band_hz: tuple, peak: float, fade_s: float,
                           seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Band-limited random reference: random-phase, equal-amplitude lines of the record's FFT grid
    inside ``band_hz``, times a C2 fade-in/out of ``fade_s`` (10t³ − 15t⁴ + 6t⁵), scaled to ``peak``.
    Returns (t [s], r)."""
    n = int(round(duration_s * fs_hz))
    rng = np.random.default_rng(np.random.SeedSequence([0x24, 0xF11E, int(seed)]))
    f = np.fft.rfftfreq(n, 1 / fs_hz)
    X = np.zeros(f.size, dtype=complex)
    inb = (f >= band_hz[0]) & (f <= band_hz[1])
    X[inb] = np.exp(2j * np.pi * rng.uniform(size=int(inb.sum())))
    r = np.fft.irfft(X, n)
    t = np.arange(n) / fs_hz
    s = np.clip(np.minimum(t, t[-1] - t) / fade_s, 0.0, 1.0)
    w = s**3 * (10 - 15 * s + 6 * s * s)
    r = r * w
    return t, r * (peak / np.max(np.abs(r)))


def write_reference(path, t, r, unit: str = "mm") -> Path:
    path = Path(path)
    _write_timeseries(path, t, {f"reference_{unit}": r}, {"source": "tests/benchmarks/journey_strip.py"})
    return path


__all__ = ["Strip", "STRIPS", "get_strip", "geometry_params", "library_fields", "true_response", "Drive",
           "design_drive", "quantise", "write_lab_records", "write_sweep_csv", "write_true_sweep", "apply_voltage", "TAU_SLOW_S",
           "F_DC", "band_limited_reference", "write_reference"]
