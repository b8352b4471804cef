"""Reference signals for feedforward, with fade-in and fade-out windows.

The noncausal inverse reads the reference as the piecewise-linear interpolant of its samples,
zero outside the record: a reference that does not come to rest at both ends is seen as a jump
to zero there, and its inverse answers with a large spike (8.5 V for a 1 Hz, 0.3 mm sine on the
seed 001 actuator surrogate).  Every generator here therefore builds

    rest (``lead_s``) | fade-in (``fade_in_s``) | body | fade-out (``fade_out_s``) | rest (``tail_s``)

with a C2 "smootherstep" window ``w(x) = 10 x^3 - 15 x^4 + 6 x^5`` (value, slope and curvature
continuous), so the inverse also has the rest time it needs to pre-actuate (anticausal part,
before the start) and to settle (causal part, after the end).

Generators (amplitudes in the model's output units, e.g. mm; time in s; frequency in Hz)
    sine(amplitude, frequency_hz, duration_s, fs_hz, ...)
    multitone(amplitudes, frequencies_hz, duration_s, fs_hz, phases_deg=None, ...)
    smoothed_steps(levels, hold_s, fs_hz, transition_s=..., ...)
    from_file(path, column=None, unit="", ...)        a time record (.csv/.npz/.mat), faded and padded
    fade(t, y, fade_in_s, fade_out_s)                window an existing record
All return a :class:`Reference` (``t``, ``y``, ``body`` mask of the unfaded part, ``.save()``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._errors import InversionError

__all__ = ["Reference", "sine", "multitone", "smoothed_steps", "from_file", "fade", "smootherstep",
           "edge_jump", "DEFAULT_UNIT"]

#: Unit of a reference saved without one: the feedforward reference is a desired actuator tip
#: displacement, in SI.
DEFAULT_UNIT = "m"


def smootherstep(x: Any) -> np.ndarray:
    """``10x^3 - 15x^4 + 6x^5`` on [0, 1], clipped outside (C2 ramp from 0 to 1)."""
    x = np.clip(np.asarray(x, dtype=float), 0.0, 1.0)
    return x * x * x * (10.0 + x * (-15.0 + 6.0 * x))


@dataclass(frozen=True, eq=False)
class Reference:
    """A sampled reference with its fade windows.

    Attributes
    ----------
    t : ndarray
        Sample times [s], uniform, starting at 0.
    y : ndarray
        Reference [model output units, e.g. mm].
    body : ndarray of bool
        Samples between the end of the fade-in and the start of the fade-out (where tracking
        is judged).
    fade_in_s, fade_out_s, lead_s, tail_s : float
        Window and rest lengths [s].
    description : str
    unit : str
        Unit of ``y`` (e.g. ``"mm"``; letters and digits, as a time-record column suffix); empty:
        saved as :data:`DEFAULT_UNIT`.
    """

    t: np.ndarray
    y: np.ndarray
    body: np.ndarray
    fade_in_s: float
    fade_out_s: float
    lead_s: float
    tail_s: float
    description: str = ""
    unit: str = ""
    metadata: dict = field(default_factory=dict)

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])

    def save(self, path: Any) -> Path:
        """Write the reference as a time record (:class:`physmodel.data.timerecord.TimeRecord`):
        columns ``time_s, reference_<unit>`` (``unit`` empty: :data:`DEFAULT_UNIT`), the fade
        windows and the description as metadata; .csv, .npz or .mat by extension, atomically."""
        from physmodel.data.timerecord import TimeRecord

        meta = {"description": self.description, "fade_in_s": f"{self.fade_in_s:g}",
                "fade_out_s": f"{self.fade_out_s:g}", "lead_s": f"{self.lead_s:g}",
                "tail_s": f"{self.tail_s:g}", **self.metadata}
        rec = TimeRecord(self.t, {"reference": self.y}, {"reference": self.unit or DEFAULT_UNIT}, meta)
        return rec.save(path)


def _positive(name: str, v: Any, allow_zero: bool = False) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise InversionError(f"{name} must be a number; got {v!r}") from None
    if not math.isfinite(x) or x < 0 or (x == 0 and not allow_zero):
        raise InversionError(f"{name} must be {'>= 0' if allow_zero else '> 0'} and finite; got {v!r}")
    return x


def _assemble(body_fn: Any, duration_s: float, fs_hz: float, fade_in_s: float, fade_out_s: float,
              lead_s: float, tail_s: float, description: str, unit: str) -> Reference:
    fs = _positive("fs_hz", fs_hz)
    dur = _positive("duration_s", duration_s)
    fi = _positive("fade_in_s", fade_in_s, True)
    fo = _positive("fade_out_s", fade_out_s, True)
    lead = _positive("lead_s", lead_s, True)
    tail = _positive("tail_s", tail_s, True)
    if fi + fo > dur:
        raise InversionError(
            f"fade_in_s + fade_out_s = {fi + fo:g} s exceeds duration_s = {dur:g} s (the signal "
            "would never reach full amplitude)")
    total = lead + dur + tail
    n = int(round(total * fs)) + 1
    t = np.arange(n) / fs
    tau = t - lead                                   # time since the signal starts
    y = np.zeros(n)
    on = (tau >= 0) & (tau <= dur)
    y[on] = body_fn(tau[on])
    w = np.ones(n)
    if fi > 0:
        w *= smootherstep(tau / fi)
    if fo > 0:
        w *= smootherstep((dur - tau) / fo)
    y *= w * on
    body = (tau >= fi) & (tau <= dur - fo)
    return Reference(t, y, body, fi, fo, lead, tail, description, unit)


def sine(amplitude: float, frequency_hz: float, duration_s: float, fs_hz: float, *,
         phase_deg: float = 0.0, offset: float = 0.0, fade_in_s: float | None = None,
         fade_out_s: float | None = None, lead_s: float = 1.0, tail_s: float = 1.0,
         unit: str = "") -> Reference:
    """``offset + amplitude sin(2 pi f tau + phase)`` for ``duration_s``, faded and padded with rest.

    Parameters
    ----------
    amplitude : float
        [output units]
    frequency_hz : float
        [Hz], below the Nyquist frequency ``fs_hz/2``.
    duration_s : float
        Length of the signal including the fades [s].
    fs_hz : float
        Sampling rate [Hz].
    phase_deg, offset : float
        Phase [deg] and offset [output units] (the offset is faded with the sine).
    fade_in_s, fade_out_s : float, optional
        Window lengths [s]; default two periods each.
    lead_s, tail_s : float
        Rest before and after [s] (pre-actuation and settling room for the inverse).
    """
    f = _positive("frequency_hz", frequency_hz)
    if f >= _positive("fs_hz", fs_hz) / 2:
        raise InversionError(f"frequency_hz = {f:g} must be below fs_hz/2 = {fs_hz / 2:g}")
    fi = 2.0 / f if fade_in_s is None else fade_in_s
    fo = 2.0 / f if fade_out_s is None else fade_out_s
    ph = math.radians(float(phase_deg))
    return _assemble(lambda tau: offset + amplitude * np.sin(2 * np.pi * f * tau + ph), duration_s,
                     fs_hz, fi, fo, lead_s, tail_s,
                     f"sine {amplitude:g} {unit} at {f:g} Hz".replace("  ", " "), unit)


def multitone(amplitudes: Any, frequencies_hz: Any, duration_s: float, fs_hz: float, *,
              phases_deg: Any = None, fade_in_s: float | None = None, fade_out_s: float | None = None,
              lead_s: float = 1.0, tail_s: float = 1.0, unit: str = "") -> Reference:
    """Sum of sines ``sum_i a_i sin(2 pi f_i tau + phi_i)``, faded and padded (fades default to two
    periods of the lowest frequency).  Amplitudes [output units], frequencies [Hz], phases [deg]."""
    a = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    f = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    ph = np.zeros_like(f) if phases_deg is None else np.atleast_1d(np.asarray(phases_deg, dtype=float))
    if not (a.size == f.size == ph.size and a.size > 0):
        raise InversionError(
            f"multitone needs as many amplitudes, frequencies and phases; got {a.size}, {f.size}, {ph.size}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(f)) and np.all(np.isfinite(ph))):
        raise InversionError("multitone amplitudes, frequencies and phases must be finite")
    fs = _positive("fs_hz", fs_hz)
    if np.any(f <= 0) or np.any(f >= fs / 2):
        raise InversionError(f"frequencies must lie in (0, fs_hz/2 = {fs / 2:g}) Hz; got {f.tolist()}")
    fmin = float(np.min(f))
    fi = 2.0 / fmin if fade_in_s is None else fade_in_s
    fo = 2.0 / fmin if fade_out_s is None else fade_out_s
    w = 2 * np.pi * f
    phr = np.radians(ph)

    def body(tau: np.ndarray) -> np.ndarray:
        return np.sin(np.outer(tau, w) + phr) @ a

    desc = "multitone " + " + ".join(f"{ai:g}@{fi_:g} Hz" for ai, fi_ in zip(a, f))
    return _assemble(body, duration_s, fs, fi, fo, lead_s, tail_s, desc, unit)


def smoothed_steps(levels: Any, hold_s: float, fs_hz: float, *, transition_s: float = 0.5,
                   lead_s: float = 1.0, tail_s: float = 1.0, unit: str = "") -> Reference:
    """A staircase from rest through ``levels`` and back to rest, each transition a C2 ramp.

    Parameters
    ----------
    levels : sequence of float
        Plateau values [output units], in order.
    hold_s : float
        Length of each plateau (after its transition) [s].
    fs_hz : float
        [Hz]
    transition_s : float
        Length of every ramp (from rest, between plateaus, back to rest) [s]; it acts as the
        fade-in (first ramp) and fade-out (last ramp).
    """
    lv = np.atleast_1d(np.asarray(levels, dtype=float))
    if lv.size == 0 or not np.all(np.isfinite(lv)):
        raise InversionError(f"levels must be a non-empty list of finite values; got {levels!r}")
    hold = _positive("hold_s", hold_s)
    tr = _positive("transition_s", transition_s)
    seq = np.concatenate(([0.0], lv, [0.0]))
    starts = np.arange(seq.size - 1) * (tr + hold)       # ramp k from seq[k] to seq[k+1]
    duration = float(starts[-1] + tr)

    def body(tau: np.ndarray) -> np.ndarray:
        y = np.full(tau.shape, seq[0])
        for k in range(seq.size - 1):        # a handful of ramps; each one vectorised
            y = y + (seq[k + 1] - seq[k]) * smootherstep((tau - starts[k]) / tr)
        return y

    ref = _assemble(body, duration, fs_hz, 0.0, 0.0, lead_s, tail_s,
                    f"smoothed steps {lv.tolist()} (hold {hold:g} s, ramps {tr:g} s)", unit)
    tau = ref.t - lead_s
    body_mask = (tau >= tr) & (tau <= duration - tr)
    return Reference(ref.t, ref.y, body_mask, tr, tr, lead_s, tail_s, ref.description, unit)


def fade(t: Any, y: Any, fade_in_s: float, fade_out_s: float, *, lead_s: float = 0.0,
         tail_s: float = 0.0, unit: str = "", description: str = "faded record") -> Reference:
    """Window an existing uniformly sampled record with C2 fades and pad it with rest.

    ``t`` [s] uniform; ``y`` [output units].  The first ``fade_in_s`` and the last ``fade_out_s``
    seconds are multiplied by the rising / falling window.
    """
    ta = np.asarray(t, dtype=float)
    ya = np.asarray(y, dtype=float)
    if ta.ndim != 1 or ta.shape != ya.shape or ta.size < 2:
        raise InversionError(f"t and y must be 1-D arrays of equal length >= 2; got {ta.shape}, {ya.shape}")
    if not (np.all(np.isfinite(ta)) and np.all(np.isfinite(ya))):
        raise InversionError("t and y must be finite")
    dt = (ta[-1] - ta[0]) / (ta.size - 1)
    if not dt > 0 or np.max(np.abs(np.diff(ta) - dt)) > 1e-6 * dt:
        raise InversionError("t must be uniformly spaced and increasing (resample the record first)")
    y0 = ya
    tau = ta - ta[0]

    def body(x: np.ndarray) -> np.ndarray:
        return np.interp(x, tau, y0)

    return _assemble(body, float(tau[-1]), 1.0 / dt, fade_in_s, fade_out_s, lead_s, tail_s,
                     description, unit)


def from_file(path: Any, *, column: str | None = None, fade_in_s: float = 0.0, fade_out_s: float = 0.0,
              lead_s: float = 0.0, tail_s: float = 0.0, unit: str = "") -> Reference:
    """A reference from a time-record file (.csv, .npz or .mat as
    :func:`physmodel.data.timerecord.read_record` reads them: ``time_s`` and value columns
    ``<name>_<unit>``), optionally faded and padded.

    ``column``: the value column or channel name (default: the first one).  ``unit``: the unit of
    the returned reference; a column in another unit of the same kind (``target_m`` for
    ``unit="mm"``) is converted, one of another kind is refused.  Empty: the column's own unit.
    A column without a unit suffix (a bare ``reference`` written by older versions of
    :meth:`Reference.save`, or ``target`` in a hand-made file) is taken to be in ``unit`` (empty:
    :data:`DEFAULT_UNIT`).

    Raises
    ------
    IPMCError
        naming the file and the problem (a malformed record, a missing column, a unit mismatch).
    """
    from physmodel.data.timerecord import read_record
    from physmodel.data.units import UNITS
    from physmodel.errors import IPMCError

    rec = read_record(path, unitless=unit or DEFAULT_UNIT)
    if column is None:
        name = next(iter(rec.channels))
    else:
        try:
            name = rec.resolve(column)
        except IPMCError:
            raise InversionError(f"{path}: no column {column!r}; found {rec.columns_names()}") from None
    y = rec.channels[name]
    have = rec.units[name]
    if unit and unit != have:
        if have not in UNITS or unit not in UNITS or UNITS[have][0] != UNITS[unit][0]:
            raise InversionError(f"{path}: column {name}_{have} is in {have!r}, which cannot be converted to the "
                                 f"requested unit {unit!r}")
        y = y * (UNITS[have][1] / UNITS[unit][1])
    return fade(rec.t, y, fade_in_s, fade_out_s, lead_s=lead_s, tail_s=tail_s,
                unit=unit or have, description=f"{Path(path).name}:{name}_{have}")


def edge_jump(y: Any) -> float:
    """How abruptly a record leaves and returns to rest (0 = smoothly, 1 = a full jump or kink).

    The larger of ``|y|`` at the first and last nonzero samples relative to ``max|y|`` (a jump
    from or to zero, including at the record's ends, where the inverse sees the signal drop to
    zero) and the first differences there relative to the largest one (a kink: a sine started at
    zero with its full slope).  A faded reference scores ~1e-6 or less.
    """
    ya = np.asarray(y, dtype=float)
    nz = np.flatnonzero(ya)
    if nz.size == 0:
        return 0.0
    peak = float(np.max(np.abs(ya)))
    ext = np.concatenate(([0.0], ya, [0.0]))            # rest beyond both ends
    d = np.abs(np.diff(ext))
    i0, i1 = int(nz[0]), int(nz[-1])
    value = max(abs(float(ya[i0])), abs(float(ya[i1]))) / peak
    kink = max(d[i0 + 1], d[i1]) / float(np.max(d)) if ya.size > 1 else 0.0
    return max(value, kink)
