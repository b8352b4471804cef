"""Time-domain virtual experiments with the infinite-dimensional models.

The exact transfer functions (tanh/sqrt terms) have no finite state space, so a simulation first
builds a **realisation**: a stable rational approximation fitted by vector fitting (Gustavsen &
Semlyen 1999, real-valued, with unstable poles flipped) to the exact response on a log grid that
covers the simulation's band (from well below 1/duration to well above the Nyquist frequency)
plus the closed-form DC value.  Its order grows until the maximum relative error on an
interleaved validation grid is below ``tol`` (default 1e-4); the achieved error is recorded and
a realisation that cannot reach it raises :class:`RealizationError`.

Responses that vanish at DC (sensor current, terminal current) are fitted as R(s) = T(s)/s,
strictly proper, and realised as T(s) = s·R(s) (exact differentiation of the modal states).

Simulation is exact for the realisation: each modal state x' = a x + u is discretised in closed
form for a first-order-hold (linearly interpolated, default) or zero-order-hold input and run
with ``scipy.signal.lfilter`` — no Python loop over samples.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import signal
from threadpoolctl import threadpool_limits

from ..errors import IPMCError
from ..numerics import weighted_complex_lstsq
from .timerecord import TimeRecord, uniform_interval


class RealizationError(IPMCError):
    """Vector fitting could not reach the requested accuracy."""


# --------------------------------------------------------------------------- vector fitting
def _basis(s, poles):
    """Real-valued VF basis: one column per real pole, two per complex pair (Im > 0)."""
    cols = []
    for a in poles:
        if a.imag == 0:
            cols.append(1.0 / (s - a.real))
        else:
            p1 = 1.0 / (s - a)
            p2 = 1.0 / (s - np.conj(a))
            cols.append(p1 + p2)
            cols.append(1j * p1 - 1j * p2)
    return np.stack(cols, axis=1)


def _block_state(poles, ctilde):
    """Real state matrix, input and output rows of the VF basis (for the relocation step)."""
    n = sum(1 if a.imag == 0 else 2 for a in poles)
    A = np.zeros((n, n))
    b = np.zeros(n)
    i = 0
    for a in poles:
        if a.imag == 0:
            A[i, i] = a.real
            b[i] = 1.0
            i += 1
        else:
            A[i:i + 2, i:i + 2] = [[a.real, a.imag], [-a.imag, a.real]]
            b[i] = 2.0
            i += 2
    return A, b, ctilde


def _pairs(eigs):
    """Stable, conjugate-reduced pole list (Im >= 0), unstable ones mirrored."""
    eigs = np.where(eigs.real > 0, -eigs.real + 1j * eigs.imag, eigs)
    out = []
    for e in eigs:
        if abs(e.imag) <= 1e-10 * max(abs(e), 1e-300):
            out.append(complex(e.real, 0.0))
        elif e.imag > 0:
            out.append(complex(e))
    return np.array(sorted(out, key=abs))


def vector_fit(s, H, n_poles: int, weight=None, iterations: int = 15, direct: bool = True):
    """Fit H(s) ≈ Σ r_m/(s − a_m) + d with stable poles.  Returns (poles, residues, d).

    ``poles``/``residues`` list one member of each conjugate pair (Im ≥ 0).  ``weight`` defaults to
    1/|H| (relative error).
    """
    s = np.asarray(s, dtype=complex)
    H = np.asarray(H, dtype=complex)
    if weight is None:
        weight = 1.0 / np.maximum(np.abs(H), 1e-300)
    w_im = np.abs(s.imag[s.imag > 0])
    lo, hi = np.log10(w_im.min()), np.log10(w_im.max())
    n_pairs = max(n_poles // 2, 1)
    beta = np.logspace(lo, hi, n_pairs)
    poles = np.array([complex(-b / 100.0, b) for b in beta])
    if n_poles % 2:
        poles = np.concatenate([[complex(-10**lo, 0.0)], poles])
    for _ in range(iterations):
        Phi = _basis(s, poles)
        cols = [Phi]
        if direct:
            cols.append(np.ones((s.size, 1)))
        cols.append(-H[:, None] * Phi)
        x = weighted_complex_lstsq(np.hstack(cols), H, weight)
        ct = x[-Phi.shape[1]:]
        A, b, c = _block_state(poles, ct)
        poles = _pairs(np.linalg.eigvals(A - np.outer(b, c)))
    Phi = _basis(s, poles)
    M = np.hstack([Phi, np.ones((s.size, 1))]) if direct else Phi
    x = weighted_complex_lstsq(M, H, weight)
    res = []
    i = 0
    for a in poles:
        if a.imag == 0:
            res.append(complex(x[i], 0.0))
            i += 1
        else:
            res.append(complex(x[i], x[i + 1]))
            i += 2
    d = float(x[-1]) if direct else 0.0
    return poles, np.array(res), d


def _eval_modal(s, poles, residues, d):
    s = np.asarray(s, dtype=complex)
    out = np.full(s.shape, d, dtype=complex)
    for a, r in zip(poles, residues):
        if a.imag == 0:
            out += r.real / (s - a.real)
        else:
            out += r / (s - a) + np.conj(r) / (s - np.conj(a))
    return out


@dataclass(frozen=True)
class Realization:
    """A stable rational (modal) realisation of an exact transfer function over a band.

    T(s) = Σ r_m/(s − a_m) + conj + d, poles with Re < 0; one member per conjugate pair kept.
    """

    poles: np.ndarray
    residues: np.ndarray
    direct: float
    band_hz: tuple
    max_rel_error: float
    description: str = ""

    @property
    def order(self) -> int:
        return int(sum(1 if a.imag == 0 else 2 for a in self.poles))

    def frequency_response(self, frequency_hz) -> np.ndarray:
        return _eval_modal(2j * np.pi * np.asarray(frequency_hz, dtype=float), self.poles, self.residues, self.direct)

    def to_control(self):
        """A python-control ``StateSpace`` in real block-diagonal form."""
        import control

        n = self.order
        A = np.zeros((n, n))
        B = np.zeros((n, 1))
        C = np.zeros((1, n))
        i = 0
        for a, r in zip(self.poles, self.residues):
            if a.imag == 0:
                A[i, i], B[i, 0], C[0, i] = a.real, 1.0, r.real
                i += 1
            else:
                A[i:i + 2, i:i + 2] = [[a.real, a.imag], [-a.imag, a.real]]
                B[i, 0] = 2.0
                C[0, i], C[0, i + 1] = r.real, r.imag
                i += 2
        return control.ss(A, B, C, [[self.direct]])

    def simulate(self, t, u, hold: str = "foh", initial: str = "rest") -> np.ndarray:
        """Output for input samples ``u`` at uniform times ``t`` [s].

        ``hold``: "foh" (input linear between samples) or "zoh" (piecewise constant).
        ``initial``: "rest" (zero state) or "steady" (steady state for the constant input u[0]).
        """
        t = np.asarray(t, dtype=float)
        u = np.asarray(u, dtype=float)
        dt = check_uniform_time(t)
        if u.shape != t.shape:
            raise IPMCError(f"input has shape {u.shape} but t has shape {t.shape}")
        if not np.all(np.isfinite(u)):
            raise IPMCError(f"input contains NaN or inf at samples {np.flatnonzero(~np.isfinite(u))[:5].tolist()}")
        if hold not in ("foh", "zoh"):
            raise IPMCError(f"hold must be 'foh' or 'zoh', got {hold!r}")
        if initial not in ("rest", "steady"):
            raise IPMCError(f"initial must be 'rest' or 'steady', got {initial!r}")
        y = np.full(u.shape, self.direct) * u
        for a, r in zip(self.poles, self.residues):
            x = _modal_states(a, dt, u, hold, initial)
            y += (r.real * x.real) if a.imag == 0 else 2.0 * (r * x).real
        return y


def _modal_states(a: complex, h: float, u: np.ndarray, hold: str, initial: str) -> np.ndarray:
    """Exact samples of x' = a x + u for a held input (closed-form discretisation)."""
    e = np.exp(a * h)
    # integrals of e^{a(h-τ)} over one step, and of (τ/h) e^{a(h-τ)}
    ah = a * h
    if abs(ah) < 1e-5:
        I0 = h * (1 + ah / 2 + ah**2 / 6)
        I1 = h * (0.5 + ah / 6 + ah**2 / 24)
    else:
        I0 = (e - 1) / a
        I1 = (e - 1 - ah) / (a * ah)
    if hold == "zoh":
        b0, b1 = I0, 0.0
    else:
        b0, b1 = I0 - I1, I1
    x0 = (-u[0] / a) if initial == "steady" else 0.0
    # x[k+1] = e x[k] + b0 u[k] + b1 u[k+1];  x[0] = x0
    v = np.empty(u.size, dtype=complex)
    v[0] = 0.0
    v[1:] = b0 * u[:-1] + b1 * u[1:]
    zi = np.array([x0], dtype=complex)
    x, _ = signal.lfilter([1.0], [1.0, -e], v, zi=zi)
    return x


def check_uniform_time(t) -> float:
    """The sampling interval [s] of uniform times ``t`` [s]: :func:`~physmodel.data.timerecord.uniform_interval`."""
    return uniform_interval(t)


def realize(fn: Callable[[np.ndarray], np.ndarray], band_hz: tuple[float, float], dc_value: float | None = None,
            derivative: bool = False, tol: float = 1e-4, max_order: int = 60, points_per_decade: int = 24,
            description: str = "") -> Realization:
    """Fit a stable modal realisation to ``fn(s)`` (vectorised over complex ``s`` [1/s]).

    ``band_hz``: (f_lo, f_hi) of the fit.  ``dc_value``: the closed-form value at s = 0 (added as a
    data point).  ``derivative``: fit fn(s)/s strictly proper and realise s·R(s) (for responses
    that vanish at DC).  Raises :class:`RealizationError` if ``tol`` is not reached by ``max_order``.
    """
    f_lo, f_hi = map(float, band_hz)
    if not (0 < f_lo < f_hi and np.isfinite(f_hi)):
        raise IPMCError(f"band_hz must satisfy 0 < f_lo < f_hi, got {band_hz!r}")
    n = max(int(np.ceil(np.log10(f_hi / f_lo) * points_per_decade)), 20)
    f_fit = np.logspace(np.log10(f_lo), np.log10(f_hi), n)
    f_val = np.sqrt(f_fit[1:] * f_fit[:-1])
    s_fit = 2j * np.pi * f_fit
    s_val = 2j * np.pi * f_val
    H_fit = np.asarray(fn(s_fit), dtype=complex)
    H_val = np.asarray(fn(s_val), dtype=complex)
    target_fit = H_fit / s_fit if derivative else H_fit
    s_data = s_fit
    if dc_value is not None and not derivative:
        s_data = np.concatenate([[0.0 + 0.0j], s_fit])
        target_fit = np.concatenate([[dc_value], target_fit])
    with threadpool_limits(limits=1, user_api="blas"):  # small tall solves: threads only stall
        best = None
        order = 6
        while order <= max_order:
            poles, res, d = vector_fit(s_data, target_fit, order, direct=not derivative)
            if derivative:
                # s·r/(s − a) = r + r a/(s − a)
                d = float(sum(r.real if a.imag == 0 else 2 * r.real for a, r in zip(poles, res)))
                res = res * poles
            err = np.max(np.abs(_eval_modal(s_val, poles, res, d) - H_val) / np.abs(H_val))
            err = max(err, np.max(np.abs(_eval_modal(s_fit, poles, res, d) - H_fit) / np.abs(H_fit)))
            if best is None or err < best[-1]:
                best = (poles, res, d, err)
            if err <= tol:
                break
            order += 4
    poles, res, d, err = best
    if err > tol:
        raise RealizationError(
            f"vector fitting reached a max relative error of {err:.2e} (> tol={tol:g}) with up to "
            f"{max_order} poles over {f_lo:g}-{f_hi:g} Hz; widen tol or raise max_order")
    return Realization(poles, res, d, (f_lo, f_hi), float(err), description)


# --------------------------------------------------------------------------- experiments
@dataclass(frozen=True)
class TimeSeries:
    """Result of a virtual experiment (SI units, names and units in the fields)."""

    t: np.ndarray
    input: np.ndarray
    output: np.ndarray
    input_name: str
    input_unit: str
    output_name: str
    output_unit: str
    clean_output: np.ndarray | None = None
    clean_input: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)

    def columns(self) -> dict:
        cols = {"time_s": self.t, f"{self.input_name}_{self.input_unit}": self.input,
                f"{self.output_name}_{self.output_unit}": self.output}
        if self.clean_output is not None:
            cols[f"{self.output_name}_clean_{self.output_unit}"] = self.clean_output
        if self.clean_input is not None:
            cols[f"{self.input_name}_clean_{self.input_unit}"] = self.clean_input
        return cols

    def record(self) -> TimeRecord:
        """The series as a :class:`~physmodel.data.timerecord.TimeRecord` (its columns and metadata)."""
        return TimeRecord.from_columns(self.columns(), self.metadata)

    def to_csv(self, path) -> Path:
        """Write the ``ipmc-timeseries`` CSV (:meth:`TimeRecord.to_csv <physmodel.data.timerecord.TimeRecord.to_csv>`)."""
        return self.record().to_csv(path)

    def to_npz(self, path) -> Path:
        """Write the ``ipmc-timeseries`` NPZ (one array per column, JSON ``header``)."""
        return self.record().to_npz(path)

    def to_mat(self, path) -> Path:
        """Write the ``ipmc-timeseries`` MATLAB file (one column vector per column, ``metadata_json``)."""
        return self.record().to_mat(path)

    def save(self, path) -> Path:
        """Write by extension (.csv, .npz, .mat), atomically, through :class:`~physmodel.data.timerecord.TimeRecord`."""
        return self.record().save(path)


def model_realization(model, temperature_c: float, fs: float, duration: float, output: str = "auto",
                      set_index: int = 0, tol: float = 1e-4, chain=None) -> Realization:
    """Realise the model's main transfer function at one temperature for a simulation at ``fs`` [Hz]
    lasting ``duration`` [s].  ``output``: actuator "displacement" (M) or "current" (1/Z);
    sensor "current" (S).  ``chain``: a sensor's :class:`~physmodel.sensor.TransimpedanceChain`
    with finite op-amps (``gbw_hz``/``dc_gain``), realised with S as one transfer function
    S(s)·A(s, Z(s)) [V/m] (the amplifier's response depends on the strip's impedance Z)."""
    is_act = getattr(model, "kind", None) == "actuator"
    if output == "auto":
        output = "displacement" if is_act else "current"
    f_lo = min(1e-3, 0.01 / duration)
    f_hi = min(20.0 * fs, max(5.0 * fs, 1e5))   # beyond 100 kHz, 5 fs suffices for FOH input spectra
    if is_act and output == "displacement":
        # a model with effects has no closed-form DC limit: the fit then anchors on the lowest grid frequency
        dc = None if getattr(model, "effects", None) else float(model.dc_gain([temperature_c])["M0"][set_index, 0])
        q, deriv = "M", False
    elif output == "current":
        q, deriv, dc = ("I" if is_act else "S"), True, None
    else:
        raise IPMCError(f"output {output!r} is not available for {type(model).__name__}; "
                        f"expected {'displacement or current' if is_act else 'current'}")
    T = [float(temperature_c)]
    if chain is not None and q != "S":
        raise IPMCError(f"a transimpedance chain with finite op-amps (gbw_hz={chain.gbw_hz}, dc_gain={chain.dc_gain}) "
                        "is simulated for a sensor's current (its source is the strip's impedance); "
                        f"{type(model).__name__} output {output!r} supports only ideal op-amps")

    def fn(s):
        if chain is None:
            return model.evaluate(s, T, quantities=(q,))[q][set_index, 0]
        ev = model.evaluate(s, T, quantities=("S", "Z"))
        return ev["S"][set_index, 0] * chain.response(s, ev["Z"][set_index, 0])

    what = q if chain is None else f"{q}·A(Z) (op-amps gbw_hz={chain.gbw_hz}, dc_gain={chain.dc_gain})"
    return realize(fn, (f_lo, f_hi), dc_value=dc, derivative=deriv, tol=tol,
                   description=f"{type(model).__name__} {what} at {temperature_c:g} °C, set {model.params[set_index].name}")


def simulate(model, temperature_c: float, t, u, output: str = "auto", chain=None, output_noise_rms: float = 0.0,
             input_noise_rms: float = 0.0, seed: int | None = None, hold: str = "foh", initial: str = "rest",
             set_index: int = 0, tol: float = 1e-4, realization: Realization | None = None) -> TimeSeries:
    """Run a virtual experiment: input samples ``u`` (SI: V for actuators, m for sensors) at ``t`` [s].

    ``chain``: optional :class:`~physmodel.sensor.TransimpedanceChain` applied to a current output
    (output becomes volts); with finite op-amps (``gbw_hz``/``dc_gain``, sensors only) the chain's
    response depends on the strip's impedance and is realised together with it
    (:func:`model_realization`), so ``realization`` must then be None.  Noise: white Gaussian of the given RMS added to the recorded output
    and input (the laser/voltage measurement), seeded.
    """
    t = np.asarray(t, dtype=float)
    dt = check_uniform_time(t)
    is_act = getattr(model, "kind", None) == "actuator"
    if output == "auto":
        output = "displacement" if is_act else "current"
    if (output_noise_rms or input_noise_rms) and seed is None:
        raise IPMCError("a noisy simulation needs an explicit integer seed (reproducibility)")
    check_seed(seed)
    for k, v in (("output_noise_rms", output_noise_rms), ("input_noise_rms", input_noise_rms)):
        if not (np.isfinite(v) and v >= 0):
            raise IPMCError(f"{k}={v!r} must be a finite number >= 0")
    if chain is not None and output != "current":
        raise IPMCError("a transimpedance chain needs a current output")
    finite_opamps = chain is not None and not chain.ideal_opamps and chain.R3 != 0
    if finite_opamps and realization is not None:
        raise IPMCError(f"realization= cannot be combined with a chain of finite op-amps (gbw_hz={chain.gbw_hz}, "
                        f"dc_gain={chain.dc_gain}): the chain is realised together with the strip "
                        "(model_realization(..., chain=chain)); pass one or the other")
    if getattr(model, "effects", None) and finite_opamps:
        raise IPMCError("a model with effects cannot be simulated with a chain of finite op-amps (the chain's response "
                        "depends on the strip's impedance, which the effects change): use ideal op-amps or the plain model")
    if realization is None and getattr(model, "effects", None) and output == ("displacement" if is_act else "current"):
        from .fftsim import RestRealization  # effects (a delay, say) have no finite realisation

        realization = RestRealization(model, temperature_c)
    real = realization or model_realization(model, temperature_c, 1.0 / dt, t[-1] - t[0], output, set_index, tol,
                                            chain=chain if finite_opamps else None)
    y = real.simulate(t, u, hold=hold, initial=initial)
    out_name, out_unit = ("tip_displacement", "m") if output == "displacement" else ("current", "A")
    if chain is not None:
        if finite_opamps:
            pass                      # in the realisation already, with its bandwidth pole
        elif chain.bandwidth_hz is None:
            y = y * chain.gain
        else:
            wc = 2 * np.pi * chain.bandwidth_hz
            amp = Realization(np.array([complex(-wc, 0.0)]), np.array([complex(chain.gain * wc, 0.0)]), 0.0,
                              (0.0, np.inf), 0.0, "amplifier pole")
            y = amp.simulate(t, y, hold=hold, initial=initial)
        out_name, out_unit = "amplifier_output", "V"
    in_name, in_unit = ("voltage", "V") if is_act else ("tip_displacement", "m")
    rng = np.random.default_rng(seed)
    y_meas = y + output_noise_rms * rng.standard_normal(y.size) if output_noise_rms else y.copy()
    u = np.asarray(u, dtype=float)
    u_meas = u + input_noise_rms * rng.standard_normal(u.size) if input_noise_rms else u.copy()
    meta = {"model": type(model).__name__ + (f" (kernel={model.kernel})" if hasattr(model, "kernel") else ""),
            "parameter_set": model.params[set_index].name, "temperature_c": f"{temperature_c:g}",
            "realization": getattr(real, "summary", None) or f"order {real.order}, max rel error "
                           f"{real.max_rel_error:.1e} over {real.band_hz[0]:g}-{real.band_hz[1]:g} Hz",
            "hold": hold, "initial": initial, "output_noise_rms": f"{output_noise_rms:g}",
            "input_noise_rms": f"{input_noise_rms:g}", "seed": str(seed)}
    if chain is not None:
        meta["chain"] = (f"R1={chain.R1:g} R2={chain.R2:g} R3={chain.R3:g} bandwidth_hz={chain.bandwidth_hz} "
                         f"gbw_hz={chain.gbw_hz} dc_gain={chain.dc_gain}")
    return TimeSeries(t, u_meas, y_meas, in_name, in_unit, out_name, out_unit, y, u, meta)


#: Most samples of one time record, checked before anything is allocated.
MAX_TIME_SAMPLES = 20_000_000


def check_seed(seed) -> None:
    """A seed is None or a non-negative integer (numpy's generators refuse anything else)."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise IPMCError(f"seed must be a non-negative integer, got {seed!r}")


def time_grid(duration: float, fs: float) -> np.ndarray:
    if not (np.isfinite(duration) and duration > 0):
        raise IPMCError(f"duration={duration!r} s must be > 0")
    if not (np.isfinite(fs) and fs > 0):
        raise IPMCError(f"fs={fs!r} Hz must be > 0")
    if duration * fs > MAX_TIME_SAMPLES:
        raise IPMCError(f"duration {duration:g} s at fs {fs:g} Hz is {duration * fs:.3g} samples; at most "
                        f"{MAX_TIME_SAMPLES} per record")
    n = int(round(duration * fs)) + 1
    if n < 2:
        raise IPMCError(f"duration {duration} s at fs {fs} Hz gives fewer than 2 samples")
    return np.arange(n) / fs


def sine(model, temperature_c: float, amplitude: float, frequency_hz: float, duration: float, fs: float,
         **kw) -> TimeSeries:
    """Sinusoidal excitation from rest: u = amplitude·sin(2π f t) (V for actuators, m for sensors)."""
    if not (np.isfinite(frequency_hz) and 0 < frequency_hz < fs / 2):
        raise IPMCError(f"frequency_hz={frequency_hz!r} must be in (0, fs/2 = {fs / 2:g}) Hz")
    t = time_grid(duration, fs)
    return simulate(model, temperature_c, t, amplitude * np.sin(2 * np.pi * frequency_hz * t), **kw)


def step(model, temperature_c: float, amplitude: float, duration: float, fs: float, t_step: float = 0.0,
         **kw) -> TimeSeries:
    """A step of ``amplitude`` at ``t_step`` [s] from rest (exact under zero-order hold)."""
    t = time_grid(duration, fs)
    u = np.where(t >= t_step, amplitude, 0.0)
    kw.setdefault("hold", "zoh")
    return simulate(model, temperature_c, t, u, **kw)


def released_tip_displacement(t, w0: float, t_release: float, omega_n: float, xi: float) -> np.ndarray:
    """Tip held at ``w0`` [m] until ``t_release`` [s], then the free, damped first mode (from rest)."""
    if not (0 < xi < 1):
        raise IPMCError(f"free vibration needs an underdamped mode, xi={xi!r}")
    tau = np.asarray(t, dtype=float) - t_release
    wd = omega_n * np.sqrt(1 - xi**2)
    taup = np.maximum(tau, 0.0)
    free = w0 * np.exp(-xi * omega_n * taup) * (np.cos(wd * taup) + xi / np.sqrt(1 - xi**2) * np.sin(wd * taup))
    return np.where(tau < 0, w0, free)


def free_release(model, temperature_c: float, w0: float, t_release: float, duration: float, fs: float,
                 set_index: int = 0, **kw) -> TimeSeries:
    """Seed 000 Figs. 14-15: displace the tip by ``w0`` [m], hold, release at ``t_release`` [s].

    Sensor: the displacement (first mode at this temperature) drives the current, starting from the
    steady state of the held tip.  Actuator: the electrodes are shorted (V = 0) and the output is
    the displacement itself.
    """
    if not (np.isfinite(t_release) and 0 <= t_release < duration):
        raise IPMCError(f"t_release = {t_release!r} s must lie in [0, duration = {duration!r} s): a release "
                        "after the record ends leaves nothing to record")
    if not (np.isfinite(w0) and w0 != 0):
        raise IPMCError(f"w0 = {w0!r} m: the initial tip displacement must be finite and non-zero")
    st = model.state([temperature_c])
    wn = float(st.omega_n[set_index, 0, 0])
    xi = float(st.xi[set_index, 0, 0])
    t = time_grid(duration, fs)
    w = released_tip_displacement(t, w0, t_release, wn, xi)
    if getattr(model, "kind", None) == "actuator":
        meta = {"model": "ActuatorModel (electrodes shorted)", "parameter_set": model.params[set_index].name,
                "temperature_c": f"{temperature_c:g}", "experiment": "free release"}
        return TimeSeries(t, np.zeros_like(t), w, "voltage", "V", "tip_displacement", "m", w, np.zeros_like(t), meta)
    kw.setdefault("initial", "steady")
    ts = simulate(model, temperature_c, t, w, set_index=set_index, **kw)
    ts.metadata["experiment"] = "free release"
    return ts
