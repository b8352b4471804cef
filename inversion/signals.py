"""Checks shared by every inversion entry point: the signal, its time base and the model split.

Kept below :mod:`inversion.preview`, :mod:`inversion.batch`, :mod:`inversion.streaming` and
:mod:`inversion.scheduled` so that none of them has to import another for these helpers (the
automatic preview used to import them back from ``batch``: an import circle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from physmodel.data.timerecord import UNIFORM_RTOL, uniform_interval
from physmodel.errors import IPMCError

from ._errors import InversionError, NonFiniteSignalError, NonUniformSamplingError
from .split import InverseSplit, check_split_for, split_inverse

__all__ = ["UNIFORM_RTOL", "as_signal", "as_split", "check_finite", "sampling_interval", "signal_extremes",
           "time_base", "EXTREMES_BLOCK", "signal_fingerprint", "check_unchanged", "SignalFingerprint"]

def sampling_interval(t: Any) -> float:
    """Return the sampling interval [s] of uniformly spaced time stamps ``t`` [s] (or of a scalar
    interval): :func:`physmodel.data.timerecord.uniform_interval`, the library's one uniform-time
    check, with its default tolerance (a step within ``UNIFORM_RTOL`` of the mean step).

    Raises
    ------
    NonUniformSamplingError
        if ``t`` has fewer than 2 samples, is not finite, not increasing, or not uniform (the
        message names the offending sample and step).
    """
    try:
        return uniform_interval(t, rtol=UNIFORM_RTOL)
    except IPMCError as exc:
        raise NonUniformSamplingError(str(exc)) from None


def time_base(t: Any, u: np.ndarray) -> tuple[np.ndarray | None, float]:
    """``(time stamps or None, dt)`` for a scalar sampling interval or an array of times matching ``u``."""
    if np.ndim(t) == 0:
        return None, sampling_interval(t)
    ta = np.asarray(t, dtype=float)
    if ta.shape != u.shape:
        raise InversionError(f"t and u must have the same length; got {ta.shape} and {u.shape}")
    return ta, sampling_interval(ta)


def as_split(model: Any, improper: str, filter_bandwidth: float | None, dt: float) -> InverseSplit:
    """The model's :class:`InverseSplit` for sampling interval ``dt`` [s]: zeros the sampling cannot
    represent are treated as at infinity (:mod:`inversion.split`, "Zeros at infinity"); a split is
    returned as it is after checking that its zeros were judged right for ``dt``."""
    if isinstance(model, InverseSplit):
        return check_split_for(model, dt)
    return split_inverse(model, improper=improper, filter_bandwidth=filter_bandwidth, dt=dt)


def as_signal(u: Any, *, finite: bool = True) -> np.ndarray:
    """The signal as a finite 1-D float array of at least 2 samples (else a message naming the sample).

    ``finite=False`` skips the finiteness check (:func:`check_finite`) for a caller that proves it
    otherwise in a pass it makes anyway (:func:`signal_extremes`).
    """
    ua = np.asarray(u, dtype=float)
    if ua.ndim != 1:
        raise InversionError(f"the signal must be 1-D; got shape {ua.shape}")
    if ua.size < 2:
        raise InversionError(f"the signal must have at least 2 samples; got {ua.size}")
    return check_finite(ua) if finite else ua


def check_finite(ua: np.ndarray) -> np.ndarray:
    """``ua`` if every sample is finite, else :class:`NonFiniteSignalError` naming the first bad one."""
    # a finite sum proves every sample finite (NaN/inf propagate) without an n-sized mask;
    # only a non-finite sum (a bad sample, or overflow) needs the element-wise check
    with np.errstate(over="ignore", invalid="ignore"):
        total = float(np.add.reduce(ua))
    if math.isfinite(total):
        return ua
    _refuse_non_finite(ua)
    return ua


def _refuse_non_finite(ua: np.ndarray) -> None:
    finite = np.isfinite(ua)
    if not finite.all():
        i = int(np.flatnonzero(~finite)[0])
        raise NonFiniteSignalError(
            f"the signal must be finite; sample {i} is {ua[i]!r} (NaN/inf are not allowed: "
            "fill or interpolate gaps before inverting)")


#: Samples per block of :func:`signal_extremes` (a block's extremes and fingerprint are taken while it is in cache).
EXTREMES_BLOCK = 1 << 15

_MOD64 = 1 << 64


@dataclass(frozen=True)
class SignalFingerprint:
    """What a signal that was not copied is recognised by when it is read again: the sum,
    modulo 2**64, of its samples' 64-bit patterns (``total``), and the positions and values of
    its first maximum and first minimum (``imax``, ``vmax``, ``imin``, ``vmin``).

    Two fingerprints are equal when every field is.  Any change of one sample changes ``total``
    (its bit pattern moves by a nonzero amount below 2**64; one ulp, or ``-0.0`` for ``0.0``,
    included).  A change of several samples is seen unless it keeps ``total`` modulo 2**64 and
    both extremes where they were: an exchange or a shift of the record moves an extreme, and a
    scaling changes its value (on its own, the sum missed every exchange and shift, and a scaling
    by 2, ½, 4 … of a record whose nonzero samples times the power are a multiple of 4096, each
    pattern then moving by a multiple of 2**52).  Not seen: e.g. two samples exchanged when
    neither is an extreme.  A position-weighted sum sees those too, but cost ~0.4 ns/sample more
    (0.72 against 0.30, 2**21 samples) in every automatic preview.
    """

    total: int
    imax: int
    imin: int
    vmax: float
    vmin: float


def signal_extremes(ua: np.ndarray) -> SignalFingerprint:
    """The extremes and fingerprint of the 1-D float64 signal ``ua``, checked finite, in one pass
    that writes nothing (:class:`SignalFingerprint`: ``imax``/``imin`` are those ``np.argmax`` and
    ``np.argmin`` of the whole record give, the first occurrence).

    Each block's extremes are searched, and its samples added to the fingerprint, while it is in
    cache, instead of separate passes over the record (``np.argmax``/``np.argmin`` treat NaN as
    the extreme, so finite extremes of every block prove every sample finite: the check of
    :func:`check_finite` comes with it).  For a caller that reads the signal again later without
    a copy (the automatic preview's errors and parts, :func:`inversion.preview.auto_preview_passes`);
    the fingerprint's sum costs ~0.14 ns/sample here (2**21 samples; the extremes ~0.45).  Raises
    :class:`NonFiniteSignalError` as :func:`as_signal` does.
    """
    ua = _native_float64(ua)
    n = ua.size
    imax = imin = 0
    vmax, vmin = -math.inf, math.inf
    total = 0
    for c0 in range(0, n, EXTREMES_BLOCK):
        o = ua[c0:c0 + EXTREMES_BLOCK]
        i, j = int(np.argmax(o)), int(np.argmin(o))
        total += int(np.add.reduce(o.view(np.uint64)))
        hi, lo = float(o[i]), float(o[j])
        if not (math.isfinite(hi) and math.isfinite(lo)):
            _refuse_non_finite(ua)
        if hi > vmax:
            vmax, imax = hi, c0 + i
        if lo < vmin:
            vmin, imin = lo, c0 + j
    return SignalFingerprint(total % _MOD64, imax, imin, vmax, vmin)


def signal_fingerprint(ua: np.ndarray) -> SignalFingerprint:
    """:func:`signal_extremes` of ``ua`` (converted to native float64 first): its
    :class:`SignalFingerprint`, the same whichever function takes it."""
    return signal_extremes(ua)


def _native_float64(ua: np.ndarray) -> np.ndarray:
    """``ua`` as native-byte-order float64 (itself when it is already)."""
    ua = np.asarray(ua, dtype=np.float64)
    return ua if ua.dtype.isnative else ua.astype(ua.dtype.newbyteorder("="))


def check_unchanged(again: float | SignalFingerprint, then: float | SignalFingerprint | None, what: str, read_first: str,
                    fingerprint: str = "the sum of the output it gives") -> None:
    """Refuse a signal changed in place since it was inverted: ``again``, a fingerprint of the
    caller's array recomputed now (``fingerprint`` says which: the sum of the output recomputed from
    it in the inversion's blocks and order, or :func:`signal_fingerprint`), must equal ``then``, the same
    fingerprint taken during the inversion, bit for bit (a NaN never matches: a non-finite sum proves
    nothing, so the callers keep :func:`signal_fingerprint` where the output's sum is not finite).

    No copy of the signal is kept (it would cost a pass over the record on every inversion), so
    what is computed later from it — ``what``, e.g. the parts of the inverse or the truncation
    errors of the automatic preview — comes from the caller's array.  A change that leaves the
    fingerprint bit for bit the same is not seen (for the output's sum, e.g. two samples
    exchanged; for :class:`SignalFingerprint`, see there).  ``read_first``: what the caller could read before reusing its array.
    """
    if then is not None and again == then and (isinstance(then, SignalFingerprint) or math.isfinite(then)):
        return
    raise InversionError(
        f"{what} are recomputed when first read from the signal inverted, which is the caller's own "
        f"array (no copy is kept), and that array changed since the inversion ({fingerprint} is "
        f"{again!r}, it was {then!r}): the caller's input array was modified in place after the "
        f"inversion; invert a copy (or read {read_first} first)")
