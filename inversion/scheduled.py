"""Inversion with a time-varying temperature (temperature-scheduled model).

Approach: frozen-temperature inverses blended linearly in temperature
----------------------------------------------------------------------
Given ``model_at(T) -> G_T(s)`` and a temperature trace ``T(t)`` sampled with the signal,
the inverse is computed for a grid of temperatures ``T_1 < ... < T_m`` covering the trace
(default spacing 1 degC), each exactly as :func:`inversion.invert` does (same preview), and
the outputs are blended sample by sample with piecewise-linear ("hat") weights in ``T(t)``:

    y(t) = sum_i w_i(T(t)) H_{T_i}[u](t),   w_i = hat function of node i.

Properties:

* at a constant temperature equal to a grid node it *is* the fixed-temperature inverse, and
  between nodes it interpolates the inverse linearly in T (error ~ dT_grid^2/8 d2y/dT2);
* the blend is continuous in time whenever T(t) is, so there are no switching transients,
  and every node keeps its own filter state, so no state has to be mapped between
  different realizations;
* it is the frozen-time (slowly varying) approximation of the inverse of the time-varying
  system; its error grows with ``|dT/dt|`` times the temperature sensitivity of the model and
  is negligible when the temperature changes little over the inverse's time constants
  (1/r0, a few tens of ms for the IPMC sensor) — bath drifts take seconds to minutes;
* cost and memory are those of m fixed inversions; each node is processed by chunks, so
  :func:`invert_scheduled_to` works in bounded memory like :func:`inversion.invert_to`.

The automatic preview is the largest signal-independent tolerance preview over the grid
(:func:`inversion.preview.frequency_preview`: truncation error below 1e-3 of the inverse for every
sinusoid up to the Nyquist frequency); ``preview="4/r0"`` is the largest ``4/r0(T_i)``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._discrete import Plan
from ._errors import InversionError, NonFiniteSignalError, PreviewError
from .batch import DEFAULT_CHUNK, SampledRecord
from .preview import DEFAULT_PREVIEW_TOL, frequency_preview, preview_rule, resolve_preview
from .signals import as_signal, sampling_interval, time_base
from .split import InverseSplit, split_inverse
from .streaming import StreamingInverter

__all__ = [
    "ScheduledInversionResult",
    "invert_scheduled",
    "invert_scheduled_to",
    "temperature_grid",
    "ScheduledStreamingInverter",
]


def temperature_grid(t_min: float, t_max: float, step: float = 1.0) -> np.ndarray:
    """Uniform grid of temperatures covering ``[t_min, t_max]`` with spacing <= ``step`` [degC]."""
    if not (math.isfinite(t_min) and math.isfinite(t_max)):
        raise InversionError(f"temperature range must be finite; got [{t_min}, {t_max}]")
    if not (math.isfinite(step) and step > 0):
        raise InversionError(f"grid step must be a positive number of degC; got {step!r}")
    if t_max < t_min:
        raise InversionError(f"temperature range is reversed: [{t_min}, {t_max}]")
    if t_max == t_min:
        return np.array([float(t_min)])
    m = int(math.ceil((t_max - t_min) / step - 1e-12)) + 1
    return np.linspace(t_min, t_max, max(m, 2))


def _hat_weights(grid: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (index i, weight of node i+1) so that w_i = 1 - lam, w_{i+1} = lam."""
    if grid.size == 1:
        return np.zeros(T.size, dtype=int), np.zeros(T.size)
    i = np.clip(np.searchsorted(grid, T, side="right") - 1, 0, grid.size - 2)
    lam = (T - grid[i]) / (grid[i + 1] - grid[i])
    return i, np.clip(lam, 0.0, 1.0)


def _node_weight(grid: np.ndarray, T: np.ndarray, node: int) -> np.ndarray:
    i, lam = _hat_weights(grid, T)
    w = np.where(i == node, 1.0 - lam, 0.0)
    if node > 0:
        w = w + np.where(i == node - 1, lam, 0.0)
    if grid.size == 1:
        w = np.ones(T.size)
    return w


def _check_temperature(temperature: Any, n: int) -> np.ndarray:
    Ta = np.asarray(temperature, dtype=float)
    if Ta.ndim == 0:
        Ta = np.full(n, float(Ta))
    if Ta.shape != (n,):
        raise InversionError(
            f"temperature trace must have one value per sample ({n}); got shape {Ta.shape}")
    if not np.all(np.isfinite(Ta)):
        i = int(np.flatnonzero(~np.isfinite(Ta))[0])
        raise NonFiniteSignalError(
            f"the temperature trace must be finite; sample {i} is {Ta[i]!r} degC")
    return Ta


def _splits(model_at: Callable[[float], Any], grid: np.ndarray, improper: str,
            filter_bandwidth: float | None, dt: float) -> list[InverseSplit]:
    """The split of every grid model at sampling interval ``dt`` [s] (zeros the sampling cannot
    represent treated as at infinity: :mod:`inversion.split`)."""
    out = []
    for T in grid:
        try:
            out.append(split_inverse(model_at(float(T)), improper=improper,
                                     filter_bandwidth=filter_bandwidth, dt=dt))
        except InversionError as exc:
            raise type(exc)(f"model_at({float(T):.6g} degC): {exc}") from exc
    return out


def _auto(splits: list[InverseSplit], preview: Any, dt: float, tol: float = DEFAULT_PREVIEW_TOL) -> float:
    """The preview the named rule gives over the grid [s]: the largest over the grid models
    (``"4/r0"``: the largest 4/r0; ``"auto"``: the largest signal-independent tolerance
    preview, :func:`inversion.preview.frequency_preview` up to the Nyquist frequency)."""
    if preview_rule(preview) == "4/r0":
        return max(s.auto_preview_s for s in splits)
    if preview_rule(preview) != "auto":
        return 0.0   # unused
    return max(frequency_preview(s, tol, omega_max=math.pi / dt)[0] for s in splits)


@dataclass(frozen=True, eq=False)
class ScheduledInversionResult(SampledRecord):
    """Result of :func:`invert_scheduled`.

    Attributes
    ----------
    input : ndarray
        Signal that was inverted.
    temperature : ndarray
        Temperature trace [degC].
    output : ndarray
        Blended reconstruction [model input units].
    stable_part, unstable_part : ndarray
        Blended causal and anticausal contributions.
    grid_c : ndarray
        Temperatures of the frozen inverses [degC].
    preview_s : float
        Preview used [s] (``inf`` for infinite).
    preview_samples : int or None
    r0 : ndarray
        ``r0`` of each grid model [1/s].
    dt : float
        [s]
    splits : list of InverseSplit
    notes : tuple of str
        What the inversion changed in the grid models: each zero treated as at infinity because
        the sampling cannot represent it, prefixed with the node's temperature (:mod:`inversion.split`).
    """

    input: np.ndarray
    temperature: np.ndarray
    output: np.ndarray
    stable_part: np.ndarray
    unstable_part: np.ndarray
    grid_c: np.ndarray
    preview_s: float
    preview_samples: int | None
    r0: np.ndarray
    dt: float
    splits: list
    t0: float = 0.0
    time_stamps: np.ndarray | None = None

    @property
    def notes(self) -> tuple[str, ...]:
        """What the inversion changed in the grid models (see the class doc)."""
        return tuple(f"{float(T):.6g} degC: {n}" for T, sp in zip(self.grid_c, self.splits, strict=True)
                     for n in sp.notes)


def _run_scheduled(splits: list[InverseSplit], grid: np.ndarray, dt: float, n_prev: int | None,
                   u: Any, Ta: Any, n: int, chunk: int, sink_s: Any, sink_u: Any,
                   check: bool) -> None:
    for node, sp in enumerate(splits):
        plan = Plan(sp, dt, n_prev)

        def ws(c0: int, c1: int, y: np.ndarray, _x: np.ndarray, node: int = node) -> None:
            w = _node_weight(grid, np.asarray(Ta[c0:c1], dtype=float), node)
            sink_s(c0, c1, w * y, node)

        def wu(c0: int, c1: int, y: np.ndarray, _x: np.ndarray, node: int = node) -> None:
            w = _node_weight(grid, np.asarray(Ta[c0:c1], dtype=float), node)
            sink_u(c0, c1, w * y, node)

        plan.forward(u, n, chunk, ws, check=check and node == 0)
        plan.backward(u, n, chunk, wu)


def invert_scheduled(model_at: Callable[[float], Any], t: Any, u: Any, temperature: Any, *,
                     preview: Any = "auto", grid_step: float = 1.0,
                     grid: Any = None, improper: str = "error",
                     filter_bandwidth: float | None = None, t0: float = 0.0,
                     chunk_size: int | None = None) -> ScheduledInversionResult:
    """Stable inversion with a time-varying temperature.

    Parameters
    ----------
    model_at : callable
        ``model_at(T_degC)`` -> model ``G_T`` (control.TransferFunction, StateSpace or
        (num, den)); e.g. ``surrogate.at``.
    t : array_like or float
        Uniform time stamps [s] or the sampling interval [s].
    u : array_like
        Signal to invert.
    temperature : array_like or float
        Temperature at each sample [degC] (a scalar means constant).
    preview : "auto", "inf", None or float
        As in :func:`inversion.invert`; ``"auto"`` is the largest signal-independent
        tolerance preview over the grid, ``"4/r0"`` the largest ``4/r0``.
    grid_step : float
        Spacing of the temperature grid [degC] (ignored when ``grid`` is given).
    grid : array_like, optional
        Explicit increasing grid of temperatures [degC]; must cover the trace.
    improper, filter_bandwidth
        See :func:`inversion.split_inverse`.
    t0 : float
        Start time when ``t`` is a sampling interval [s].
    chunk_size : int, optional
        Samples per chunk (default: whole record).

    Returns
    -------
    ScheduledInversionResult
    """
    ua = as_signal(u)
    n = ua.size
    Ta = _check_temperature(temperature, n)
    ta, dt = time_base(t, ua)
    g = _grid(grid, Ta, grid_step)
    splits = _splits(model_at, g, improper, filter_bandwidth, dt)
    n_prev, prev_s = resolve_preview(preview, _auto(splits, preview, dt), dt, n)
    chunk = n if chunk_size is None else int(chunk_size)
    if chunk <= 0:
        raise InversionError(f"chunk_size must be a positive integer; got {chunk_size!r}")
    stable = np.zeros(n)
    unstable = np.zeros(n)

    def add_s(c0: int, c1: int, y: np.ndarray, _node: int) -> None:
        stable[c0:c1] += y

    def add_u(c0: int, c1: int, y: np.ndarray, _node: int) -> None:
        unstable[c0:c1] += y

    _run_scheduled(splits, g, dt, n_prev, ua, Ta, n, chunk, add_s, add_u, check=False)
    return ScheduledInversionResult(
        input=ua, temperature=Ta, output=stable + unstable, stable_part=stable,
        unstable_part=unstable, grid_c=g, preview_s=prev_s, preview_samples=n_prev,
        r0=np.array([s.r0 for s in splits]), dt=dt, splits=splits, t0=float(t0),
        time_stamps=ta)


def _grid(grid: Any, Ta: np.ndarray, step: float) -> np.ndarray:
    lo, hi = float(np.min(Ta)), float(np.max(Ta))
    if grid is None:
        return temperature_grid(lo, hi, step)
    g = np.asarray(grid, dtype=float).ravel()
    if g.size == 0 or not np.all(np.isfinite(g)) or np.any(np.diff(g) <= 0):
        raise InversionError(f"grid must be a non-empty increasing list of temperatures; got {g}")
    if lo < g[0] - 1e-9 or hi > g[-1] + 1e-9:
        raise InversionError(
            f"the temperature trace spans [{lo:.6g}, {hi:.6g}] degC but the grid covers only "
            f"[{g[0]:.6g}, {g[-1]:.6g}] degC")
    return g


def invert_scheduled_to(model_at: Callable[[float], Any], dt: float, u: Any, temperature: Any,
                        out: Any, *, preview: Any = "auto", grid_step: float = 1.0,
                        grid: Any = None, improper: str = "error",
                        filter_bandwidth: float | None = None,
                        chunk_size: int = DEFAULT_CHUNK) -> np.ndarray:
    """Bounded-memory version of :func:`invert_scheduled` (``u``, ``temperature``, ``out``
    may be memory-mapped).  Returns the temperature grid [degC]."""
    dt = sampling_interval(dt)
    n = len(u)
    if len(out) != n or len(temperature) != n:
        raise InversionError(
            f"u, temperature and out must have the same length; got {n}, {len(temperature)}, {len(out)}")
    lo, hi = math.inf, -math.inf
    for c0 in range(0, n, chunk_size):
        Tc = _check_temperature(temperature[c0:c0 + chunk_size], min(chunk_size, n - c0))
        lo, hi = min(lo, float(Tc.min())), max(hi, float(Tc.max()))
    if grid is None:
        g = temperature_grid(lo, hi, grid_step)
    else:
        g = _grid(grid, np.array([lo, hi]), grid_step)
    splits = _splits(model_at, g, improper, filter_bandwidth, dt)
    n_prev, _ = resolve_preview(preview, _auto(splits, preview, dt), dt, n)
    for c0 in range(0, n, chunk_size):
        out[c0:c0 + chunk_size] = 0.0

    def add(c0: int, c1: int, y: np.ndarray, _node: int) -> None:
        out[c0:c1] = np.asarray(out[c0:c1], dtype=float) + y

    _run_scheduled(splits, g, dt, n_prev, u, temperature, n, chunk_size, add, add, check=True)
    return g


class ScheduledStreamingInverter:
    """Streaming version of :func:`invert_scheduled` (same output up to rounding).

    Parameters
    ----------
    model_at : callable
        ``model_at(T_degC)`` -> model.
    dt : float
        Sampling interval [s].
    temperature_range : (float, float)
        Range the temperature will stay in [degC] (the grid must be fixed up front).
    preview : "auto" or float
        [s]; ``"auto"`` = largest tolerance preview over the grid, ``"4/r0"`` = largest ``4/r0``.
    grid_step : float
        [degC]
    """

    def __init__(self, model_at: Callable[[float], Any], dt: float,
                 temperature_range: tuple[float, float], preview: Any = "auto", *,
                 grid_step: float = 1.0, improper: str = "error",
                 filter_bandwidth: float | None = None):
        self.grid_c = temperature_grid(float(temperature_range[0]), float(temperature_range[1]),
                                       grid_step)
        dt = sampling_interval(dt)
        splits = _splits(model_at, self.grid_c, improper, filter_bandwidth, dt)
        n_prev, prev_s = resolve_preview(preview, _auto(splits, preview, dt), dt)
        if n_prev is None:
            raise PreviewError(
                f"a streaming inverter needs a finite preview (seconds or 'auto'); got {preview!r}")
        self.dt = dt
        self.preview_s = prev_s
        self._nodes = [StreamingInverter(sp, dt, prev_s) for sp in splits]
        self.delay_samples = max(nd.delay_samples for nd in self._nodes)
        if any(nd.delay_samples != self.delay_samples for nd in self._nodes):  # pragma: no cover
            raise InversionError("grid models need different delays (mixed improper orders)")
        self._T = np.zeros(0)

    def push(self, chunk: Any, temperature: Any) -> np.ndarray:
        """Consume samples and their temperatures [degC]; return newly final output."""
        x = np.asarray(chunk, dtype=float).ravel()
        Tc = _check_temperature(temperature, x.size)
        lo, hi = self.grid_c[0], self.grid_c[-1]
        if x.size and (Tc.min() < lo - 1e-9 or Tc.max() > hi + 1e-9):
            raise InversionError(
                f"temperature {float(Tc.min() if Tc.min() < lo else Tc.max()):.6g} degC is outside "
                f"the declared range [{lo:.6g}, {hi:.6g}] degC")
        self._T = np.concatenate((self._T, Tc))
        return self._blend([nd.push(x) for nd in self._nodes])

    def flush(self) -> np.ndarray:
        """End the signal and return the remaining output."""
        return self._blend([nd.flush() for nd in self._nodes])

    def _blend(self, outs: list[np.ndarray]) -> np.ndarray:
        m = outs[0].size
        Tm, self._T = self._T[:m], self._T[m:]
        y = np.zeros(m)
        for node, o in enumerate(outs):
            y += _node_weight(self.grid_c, Tm, node) * o
        return y
