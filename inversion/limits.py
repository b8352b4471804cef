"""Limits on what an inversion may ask of the hardware: never a silent 42 V.

An IPMC strip tolerates about 2-3 V; a feedforward computed from a poor surrogate or a
too-short preview can demand tens of volts, and a decoded displacement can leave the range
the strip can physically reach.  :class:`Limits` states the bounds, :func:`check_limits`
finds the first sample that violates each one, and either refuses (:class:`LimitError`, an
``IPMCError``) or warns (:class:`LimitWarning`), always naming the sample, its time and value.

``inversion.feedforward(..., limits=Limits(max_voltage=2.5, max_rate=50))`` and
``inversion.decode_sensor(..., limits=Limits(output_range=(-2, 2)))`` apply them to
``result.output``; the report is ``result.limit_report``.

Safe by default: :func:`inversion.feedforward` without ``limits`` refuses a drive beyond
:data:`DEFAULT_MAX_VOLTAGE` (3 V, also ``ipmc feedforward --max-voltage``'s default); dropping it
takes an explicit ``limits="off"`` (or ``Limits()``, which only measures the peaks).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ._errors import InversionError

__all__ = ["Limits", "LimitReport", "LimitViolation", "LimitError", "LimitWarning", "check_limits",
           "DEFAULT_MAX_VOLTAGE", "default_drive_limits"]

_ACTIONS = ("error", "warn")

#: The drive voltage an IPMC strip is assumed to tolerate when nothing else is said: the default
#: ``max_voltage`` of :func:`inversion.feedforward` and of ``ipmc feedforward --max-voltage``, and
#: the level above which ``ipmc excite`` warns. [V]
DEFAULT_MAX_VOLTAGE = 3.0


class LimitError(InversionError):
    """A computed signal violates a stated limit (the message names the first sample)."""


class LimitWarning(UserWarning):
    """A computed signal violates a stated limit and ``action="warn"`` was chosen."""


@dataclass(frozen=True)
class Limits:
    """Bounds on a computed signal (the inversion's output).

    Parameters
    ----------
    max_voltage : float, optional
        Largest allowed ``|output|`` [output units; V for a feedforward].  Applies to any
        output: for decoding it bounds ``|displacement|``.
    max_rate : float, optional
        Largest allowed ``|d output/dt|`` (first differences / dt) [output units / s].
    output_range : (float, float), optional
        Allowed interval ``[lo, hi]`` of the output [output units] (e.g. the displacement range
        a decoded signal must stay in).
    action : {"error", "warn"}
        Refuse (raise :class:`LimitError`) or warn (:class:`LimitWarning`) on a violation.
    """

    max_voltage: float | None = None
    max_rate: float | None = None
    output_range: tuple[float, float] | None = None
    action: str = "error"

    def __post_init__(self) -> None:
        for name in ("max_voltage", "max_rate"):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise InversionError(f"Limits.{name} must be a positive finite number; got {v!r}")
        if self.output_range is not None:
            try:
                lo, hi = (float(x) for x in self.output_range)
            except (TypeError, ValueError):
                raise InversionError(
                    f"Limits.output_range must be a pair (lo, hi); got {self.output_range!r}") from None
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise InversionError(f"Limits.output_range needs finite lo < hi; got {self.output_range!r}")
            object.__setattr__(self, "output_range", (lo, hi))
        if self.action not in _ACTIONS:
            raise InversionError(f"Limits.action must be one of {_ACTIONS}; got {self.action!r}")

    @property
    def empty(self) -> bool:
        return self.max_voltage is None and self.max_rate is None and self.output_range is None


@dataclass(frozen=True)
class LimitViolation:
    """First violation of one limit.

    Attributes
    ----------
    kind : str
        ``"max_voltage"``, ``"max_rate"``, ``"output_range"``.
    index : int
        First violating sample.
    time_s : float
        Its time [s].
    value : float
        The violating value (output, or rate) [output units or output units / s].
    limit : float
        The bound it exceeded.
    count : int
        Number of violating samples.
    """

    kind: str
    index: int
    time_s: float
    value: float
    limit: float
    count: int

    def describe(self, what: str, unit: str) -> str:
        if self.kind == "max_rate":
            return (f"{what} changes at {self.value:.4g} {unit}/s at sample {self.index} "
                    f"(t = {self.time_s:.6g} s), above max_rate = {self.limit:.4g} {unit}/s "
                    f"({self.count} samples violate it)")
        if self.kind == "output_range":
            return (f"{what} is {self.value:.4g} {unit} at sample {self.index} (t = {self.time_s:.6g} s), "
                    f"outside the allowed range ending at {self.limit:.4g} {unit} "
                    f"({self.count} samples violate it)")
        return (f"{what} is {self.value:.4g} {unit} at sample {self.index} (t = {self.time_s:.6g} s), "
                f"beyond max_voltage = ±{self.limit:.4g} {unit} ({self.count} samples violate it)")


@dataclass(frozen=True)
class LimitReport:
    """Result of :func:`check_limits`.

    Attributes
    ----------
    ok : bool
        No limit violated.
    violations : list of LimitViolation
        First violation of each violated limit, earliest first.
    peak : float
        ``max|output|`` [output units].
    peak_rate : float
        ``max|d output/dt|`` [output units / s].
    message : str
        Human-readable summary ("" when ok).
    limits : Limits or None
        The limits checked (None: none, the peaks were only measured).
    """

    ok: bool
    violations: list = field(default_factory=list)
    peak: float = 0.0
    peak_rate: float = 0.0
    message: str = ""
    limits: Limits | None = None


def check_limits(y: Any, dt: float, limits: Limits | None, *, t0: float = 0.0,
                 what: str = "output", unit: str = "") -> LimitReport:
    """Check a computed signal against ``limits``; refuse or warn on the first violation.

    Parameters
    ----------
    y : array_like
        The signal [output units].
    dt : float
        Sampling interval [s].
    limits : Limits or None
        ``None`` or empty limits only measure the peaks.
    t0 : float
        Time of sample 0 [s].
    what, unit : str
        Names used in the message (e.g. ``"feedforward voltage"``, ``"V"``).

    Raises
    ------
    LimitError
        on a violation when ``limits.action == "error"``.
    """
    ya = np.asarray(y, dtype=float)
    if ya.ndim != 1 or ya.size == 0:
        raise InversionError(f"{what} must be a non-empty 1-D array; got shape {ya.shape}")
    if not np.all(np.isfinite(ya)):
        i = int(np.flatnonzero(~np.isfinite(ya))[0])
        raise LimitError(f"{what} is not finite at sample {i} (t = {t0 + i * dt:.6g} s): {ya[i]!r}")
    rate = np.abs(np.diff(ya)) / dt if ya.size > 1 else np.zeros(0)
    peak = float(np.max(np.abs(ya)))
    peak_rate = float(np.max(rate)) if rate.size else 0.0
    if limits is None or limits.empty:
        return LimitReport(True, [], peak, peak_rate, "", limits)
    found: list[LimitViolation] = []

    def first(mask: np.ndarray, values: np.ndarray, kind: str, bound: Any, offset: int = 0) -> None:
        idx = np.flatnonzero(mask)
        if idx.size:
            i = int(idx[0])
            b = bound(i) if callable(bound) else bound
            found.append(LimitViolation(kind, i + offset, t0 + (i + offset) * dt, float(values[i]),
                                        float(b), int(idx.size)))

    if limits.max_voltage is not None:
        first(np.abs(ya) > limits.max_voltage, ya, "max_voltage", limits.max_voltage)
    if limits.max_rate is not None and rate.size:
        first(rate > limits.max_rate, rate, "max_rate", limits.max_rate, offset=1)
    if limits.output_range is not None:
        lo, hi = limits.output_range
        first((ya < lo) | (ya > hi), ya, "output_range", lambda i: lo if ya[i] < lo else hi)
    found.sort(key=lambda v: v.index)
    if not found:
        return LimitReport(True, [], peak, peak_rate, "", limits)
    msg = "; ".join(v.describe(what, unit) for v in found)
    msg += f" (peak {peak:.4g} {unit}, peak rate {peak_rate:.4g} {unit}/s)"
    if limits.action == "error":
        raise LimitError(msg + ": refused. Check the model, use a longer preview or preview='inf', "
                         "lower the reference, or relax the limits (action='warn' to proceed).")
    warnings.warn(LimitWarning(msg), stacklevel=3)
    return LimitReport(False, found, peak, peak_rate, msg, limits)


def default_drive_limits(input_unit: str = "V", action: str = "error") -> Limits:
    """The default drive limit, ``|V| <= DEFAULT_MAX_VOLTAGE``, in a model's input unit.

    Parameters
    ----------
    input_unit : str
        The unit of the drive signal (the actuator model's input), a voltage unit of
        :data:`physmodel.data.units.UNITS` (``"V"``, ``"mV"``, ...).
    action : {"error", "warn"}
        As :class:`Limits`.

    Returns
    -------
    Limits
        ``Limits(max_voltage=DEFAULT_MAX_VOLTAGE / scale)`` with ``scale`` the size of
        ``input_unit`` in volts (3000 for mV).
    """
    from physmodel.data.units import UNITS

    if input_unit not in UNITS or UNITS[input_unit][0] != "voltage":
        volts = sorted(u for u, (q, _) in UNITS.items() if q == "voltage")
        raise InversionError(f"input_unit={input_unit!r}: the drive's unit must be a voltage unit, one of {volts}")
    return Limits(max_voltage=DEFAULT_MAX_VOLTAGE / UNITS[input_unit][1], action=action)
