"""Batch stable (noncausal) inversion with infinite or finite preview.

See :mod:`inversion._discrete` for the discretisation (exact for the piecewise-linear
interpolant of the samples, zero outside the record) and the exact finite-preview
truncation; see :mod:`inversion.split` for the split of ``1/G``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from ._discrete import pass_errstate, plan_for
from ._errors import InversionError, NonFiniteSignalError
from .preview import (
    DEFAULT_PREVIEW_TOL,
    PreviewChoice,
    auto_preview_passes,
    choose_preview,
    preview_rule,
    resolve_preview,
    truncation_error,
)
from .signals import (
    SignalFingerprint,
    as_signal,
    as_split,
    check_finite,
    check_unchanged,
    sampling_interval,
    signal_fingerprint,
    time_base,
)
from .split import InverseSplit

__all__ = [
    "InversionResult",
    "invert",
    "invert_to",
    "decode_sensor",
    "feedforward",
    "resolve_preview",
    "choose_preview",
    "PreviewChoice",
    "preview_rule",
    "sampling_interval",
    "DEFAULT_CHUNK",
]

#: Samples processed per chunk (bounds the working memory to a few times 8 MiB).
DEFAULT_CHUNK = 1 << 20


class SampledRecord:
    """Mixin for result records sampled at ``dt`` from ``t0`` (or at explicit ``time_stamps``)."""

    @cached_property
    def t(self) -> np.ndarray:
        """Sample times [s]."""
        if self.time_stamps is not None:
            return self.time_stamps
        return self.t0 + self.dt * np.arange(self.input.size)


@dataclass(frozen=True, eq=False)
class InversionResult(SampledRecord):
    """Result of :func:`invert`.

    Attributes
    ----------
    t : ndarray
        Sample times [s] (built on first access when only ``dt`` was given).
    input : ndarray
        The signal that was inverted [model output units, e.g. uA for a sensor]: the caller's
        array itself for every preview, ``"auto"`` included (a 1-D float64 array; anything else
        is converted, and ``input`` is the conversion).  No copy is kept (it would cost a pass
        over the record on every inversion): what is computed from it later — the parts (below),
        and for ``preview="auto"`` the truncation errors in ``preview_choice`` and
        ``truncation_error`` — is checked against the inversion and refused
        (:class:`InversionError`) if the array was modified in place since (a fingerprint taken
        during the inversion must be the same: the sum of the output for the parts of a given
        preview, :class:`~inversion.signals.SignalFingerprint` — the sum of the samples' bit
        patterns, which sees any change of one sample, and the extremes — for the errors and parts of
        ``"auto"`` and wherever the output's sum overflowed; a change that leaves it so is not
        seen); invert
        a copy to reuse the array.  ``truncation_bound`` of ``preview="auto"`` is the choice's,
        taken at the inversion; ``discretisation_error_estimate`` (and ``truncation_error``,
        ``truncation_bound`` of a given preview) are computed from ``input`` as it is when first
        read, without a check.
    output : ndarray
        The reconstruction ``H[u]`` = ``stable_part + unstable_part`` [model input units,
        e.g. mm for a sensor, V for an actuator].
    stable_part : ndarray
        Causal contribution: feedthrough, polynomial (derivative) part and ``H_s[u]``.  When the
        anticausal pass ran block by block (a finite preview, or ``chunk_size``) the output was
        written over it, and it is recomputed when first read, with ``unstable_part`` (below).
    unstable_part : ndarray
        Anticausal contribution ``H_u[u]`` (truncated to the preview when it is finite).
        When the anticausal pass ran block by block it is not stored but recomputed when first
        read, with ``stable_part``: one more causal and anticausal pass over the signal
        inverted, the same values bit for bit as those whose sum was written to ``output``.
        Keeping them would cost record-sized arrays that nothing but these attributes reads.
        ``output`` is not read for it: the caller may edit ``output`` in place (e.g. clip a
        drive) and still read the parts of the inversion.  ``input`` is the caller's array (no
        copy is made, ``preview="auto"`` included) and the parts are recomputed from it; an
        ``input`` modified in place since the inversion is refused (:class:`InversionError`):
        for a given preview the sum of the recomputed output, summed in the same blocks and
        order as the inversion summed it (to prove it finite), must equal that sum bit for bit
        (a change that leaves it bit for bit the same is not seen, e.g. two samples exchanged);
        for ``"auto"``, and wherever that sum overflowed (every output sample finite, their
        sum not: it would prove nothing), ``input_fingerprint`` must be the same.
    preview_s : float
        Preview actually used, ``preview_samples * dt`` [s]; ``inf`` for infinite preview.
    preview_samples : int or None
        Preview in samples; ``None`` for infinite preview.
    r0 : float
        Real part of the least unstable inverse pole [1/s] (``inf`` if minimum phase).
    auto_preview_s : float
        ``4/r0`` [s] (what the seed-000 rule ``preview="4/r0"`` uses; not the automatic preview).
    dt : float
        Sampling interval [s].
    split : InverseSplit
        The model pieces (polynomial part, feedthrough, stable and anti-stable realizations).
    preview_rule : str
        ``"auto"``, ``"4/r0"``, ``"inf"`` or ``"fixed"`` (a number of seconds was given).
    preview_choice : PreviewChoice or None
        For ``preview="auto"``: the tolerance, the achieved relative truncation error and
        the bounds (see :func:`choose_preview`).
    truncation_error, truncation_bound : float
        Largest error the preview causes on this signal (exact) and its signal-independent
        bound [output units].
    t0 : float
        Time of sample 0 [s].
    time_stamps : ndarray or None
        The caller's own sample times [s] when they were given (else ``t`` is built from
        ``t0`` and ``dt``).
    limit_report : LimitReport or None
        The drive-limit check of ``output`` (:func:`~inversion.limits.check_limits`).
    notes : tuple of str
        What the inversion changed in the model (``split.notes``): each zero treated as at
        infinity because the sampling cannot represent it (:mod:`inversion.split`).
    unstable_source : ndarray or tuple
        Where ``unstable_part`` comes from: the array itself, or the ``(plan, chunk)`` that
        recomputes it from ``input`` (internal; read ``unstable_part``) [model input units].
    stable_source : ndarray or None
        The causal part itself, or None when it is recomputed with ``unstable_part``
        (internal; read ``stable_part``) [model input units].
    output_sum : float or None
        The sum of ``output`` as the block-wise pass wrote it (internal): the fingerprint the
        parts recomputed from the caller's ``input`` are checked against when
        ``input_fingerprint`` is None [model input units].
    input_fingerprint : SignalFingerprint or None
        :func:`~inversion.signals.signal_fingerprint` of ``input`` at the inversion (internal;
        ``preview="auto"``, which takes it in its extremes pass, or an output whose sum is not
        finite): what the recomputed parts are checked against instead of ``output_sum``.
    """

    input: np.ndarray
    output: np.ndarray
    preview_s: float
    preview_samples: int | None
    r0: float
    auto_preview_s: float
    dt: float
    split: InverseSplit
    t0: float = 0.0
    time_stamps: np.ndarray | None = None
    preview_rule: str = "fixed"
    preview_choice: PreviewChoice | None = None
    limit_report: Any = None
    #: the anticausal part, or ``(plan, chunk)`` that recomputes it (see ``unstable_part``)
    unstable_source: Any = field(default=None, repr=False)
    #: the causal part, or None: recomputed with the anticausal part (see ``stable_part``)
    stable_source: np.ndarray | None = field(default=None, repr=False)
    #: the sum of output as written, checked when the parts are recomputed from the caller's input
    output_sum: float | None = field(default=None, repr=False)
    #: the input's signal_fingerprint at the inversion, or None (then output_sum is checked)
    input_fingerprint: SignalFingerprint | None = field(default=None, repr=False)

    @property
    def notes(self) -> tuple[str, ...]:
        """What the inversion changed in the model (see the class doc)."""
        return self.split.notes

    @property
    def stable_part(self) -> np.ndarray:
        """Causal contribution (see the class doc)."""
        if self.stable_source is not None:
            return self.stable_source
        return self._parts[0]

    @cached_property
    def unstable_part(self) -> np.ndarray:
        """Anticausal contribution ``H_u[u]`` (see the class doc)."""
        src = self.unstable_source
        if isinstance(src, np.ndarray):
            return src
        return self._parts[1]

    @cached_property
    def _parts(self) -> tuple[np.ndarray, np.ndarray]:
        """``(stable_part, unstable_part)`` recomputed by the passes that made ``output`` (see the
        class doc) from ``input``, checked unchanged by its fingerprint or the sum of the output it
        gives (``output`` itself is not read)."""
        src = self.unstable_source
        if isinstance(src, np.ndarray):        # only the causal part was not kept
            raise InversionError("internal: a kept anticausal part without its causal part")  # pragma: no cover
        plan, chunk = src
        what = "the stable and unstable parts (result.stable_part, result.unstable_part)"
        if self.input_fingerprint is not None:
            check_unchanged(signal_fingerprint(self.input), self.input_fingerprint, what,
                            "stable_part and unstable_part", "its fingerprint (SignalFingerprint)")
        sums: list[float] = []
        stable, unstable, _ = plan.run(self.input, chunk, self.stable_source, output_sum=sums)
        if self.input_fingerprint is None:
            check_unchanged(sums[0], self.output_sum, what, "stable_part and unstable_part")
        if stable is None or unstable is None:     # pragma: no cover - keep_unstable=True keeps both
            raise InversionError("internal: the recomputation did not keep both parts")
        return stable, unstable

    @cached_property
    def truncation_error(self) -> float:
        """Largest error the finite preview causes on this signal, ``max|y_Tp - y_inf|``
        [output units] (exact for the sampled signal; 0 for infinite preview)."""
        if self.preview_choice is not None:
            return self.preview_choice.max_error
        if self.preview_samples is None or self.split.n_unstable == 0:
            return 0.0
        return float(np.max(np.abs(truncation_error(self.split, self.dt, self.input, self.preview_samples))))

    @cached_property
    def truncation_bound(self) -> float:
        """Signal-independent bound on the preview error, ``tail_l1_norm(T_p) max|u|`` [output units]
        (for ``preview="auto"`` the choice's ``tail_bound``, the same number, taken at the inversion)."""
        if self.preview_samples is None:
            return 0.0
        if self.preview_choice is not None:
            return self.preview_choice.tail_bound
        return float(self.split.tail_l1_norm(self.preview_s)) * float(np.max(np.abs(self.input)))


    @cached_property
    def discretisation_error_estimate(self) -> float:
        """Estimate of the largest error due to sampling [output units].

        ``(||h_s||_1 + ||h_u||_1)/8 * max|u[k+1] - 2u[k] + u[k-1]|`` over the interior of the
        record: the bound ``||h||_1 dt**2/8 max|u''|`` on the response to the interpolation
        error (see :mod:`inversion._discrete`) with ``u''`` estimated by second differences.
        It excludes the preview truncation, the edge transients of the record, and the
        finite-difference error of the ``"differentiate"`` mode.
        """
        return _disc_estimate(self.split, self.input, self.preview_samples)


def _disc_estimate(split: InverseSplit, u: np.ndarray, n_preview: int | None) -> float:
    if u.size < 3:
        return 0.0
    l1s, l1u = split.l1_norms()
    if n_preview == 0:
        l1u = 0.0
    # interior second differences only: the one-sample ramps to zero at the record ends are
    # part of the signal model (edge effects), not a sampling error
    d2 = float(np.max(np.abs(u[2:] - 2 * u[1:-1] + u[:-2])))
    return (l1s + l1u) * d2 / 8.0


def invert(model: Any, t: Any, u: Any, *, preview: Any = "auto", improper: str = "error",
           filter_bandwidth: float | None = None, t0: float = 0.0,
           chunk_size: int | None = None, preview_tol: float = DEFAULT_PREVIEW_TOL,
           preview_norm: str = "linf") -> InversionResult:
    """Stable inversion ``y = G^{-1}[u]`` of a uniformly sampled signal.

    Parameters
    ----------
    model : control.TransferFunction, control.StateSpace, (num, den) or InverseSplit
        Proper continuous-time SISO model ``G(s)`` (s in rad/s) mapping the quantity to
        recover to the measured one (sensor: displacement -> current; actuator: voltage ->
        displacement).  A surrogate must be evaluated first: ``surrogate.at(T)``.
    t : array_like or float
        Uniform time stamps [s] (checked), or the sampling interval ``dt`` [s].
    u : array_like
        Signal to invert (sensor output, or desired actuator output), same length as ``t``.
    preview : "auto", "4/r0", "inf", None or float
        Preview time [s] for the anticausal part: ``"auto"`` = the smallest preview whose
        truncation error on this signal is below ``preview_tol`` of the full inverse (see
        :func:`choose_preview`; the result reports it in ``preview_choice``); ``"4/r0"`` =
        the Zou–Devasia rule used in seed 000 (far too short when the anticausal residues
        are large, as for the seed 001 actuator surrogates); ``"inf"``/``None`` = full
        noncausal inverse; or a number of seconds (rounded to whole samples, must not
        exceed the record).
    improper : {"error", "filter", "differentiate"}
        Handling of a strictly proper model (see :func:`inversion.split_inverse`).
    filter_bandwidth : float, optional
        Low-pass bandwidth for ``improper="filter"`` [rad/s].
    t0 : float
        Start time when ``t`` is a sampling interval [s].
    chunk_size : int, optional
        Samples per processing chunk.  Default: the whole record in one chunk (the result
        arrays are O(n) anyway); see :func:`invert_to` for bounded-memory processing.  The
        result does not depend on it beyond rounding.
    preview_tol : float
        Tolerance of ``preview="auto"``: truncation error relative to the full inverse.
    preview_norm : {"linf", "l2"}
        Norm in which ``preview_tol`` is measured.

    Returns
    -------
    InversionResult

    Notes
    -----
    The samples are read as the piecewise-linear interpolant of the signal, zero outside the
    record; both parts of the inverse are discretised exactly for that signal (see
    :mod:`inversion._discrete`).  Taper or pad records that do not start and end near zero,
    or discard the first few stable time constants and the last ``T_p*`` seconds.

    ``invert`` checks no limit: it is the generic inverse and does not know whether its output
    is a voltage (actuator) or a displacement (sensor decoding).  For a drive use
    :func:`feedforward` (3 V limit by default); for decoding, :func:`decode_sensor` (limits on
    request); or :func:`inversion.limits.check_limits` on ``result.output``.
    """
    rule = preview_rule(preview)
    # the signal is proved finite in a pass made anyway: preview="auto" in the one that finds its
    # extremes (auto_preview_passes), any other preview by the sum of the output (below): every input sample
    # reaches its own output sample through the causal pass's b0 * u[k] (computed even for b0 = 0,
    # and 0 * NaN, 0 * inf are NaN), so a finite output proves a finite input
    ua = as_signal(u, finite=False)
    ta, dt = time_base(t, ua)
    split = as_split(model, improper, filter_bandwidth, dt)
    if chunk_size is None:
        chunk_size = ua.size
    if not (isinstance(chunk_size, int | np.integer) and chunk_size > 0):
        raise InversionError(f"chunk_size must be a positive integer; got {chunk_size!r}")
    chunk = int(chunk_size)
    choice = None
    # a non-finite input sample, or an overflow, is refused below with its index: numpy's warnings
    # inside the passes (e.g. inf - inf adding the parts, D * u overflowing) would only announce it,
    # so they are silenced there (pass_errstate) and nowhere else (not in the preview choice)
    if rule == "auto":
        # the causal pass, the preview certified from exact values of the full inverse at a
        # few samples, then the finite-preview anticausal pass (see auto_preview_passes)
        passes = auto_preview_passes(split, dt, ua, tol=preview_tol, norm=preview_norm, chunk=chunk,
                                     keep_unstable=False, finite_checked=False, keep_stable=False,
                                     quiet_passes=True)
        choice = passes.choice
        n_prev, prev_s = choice.samples, choice.seconds
        stable, unstable, output = passes.stable, passes.unstable, passes.output
        finite = passes.finite
        written_sum = passes.output_sum
        fingerprint = passes.fingerprint
        plan = passes.plan
    else:
        n_prev, prev_s = resolve_preview(preview, split, dt, ua.size)
        plan = plan_for(split, dt, n_prev)
        # the anticausal part is recomputed if it is ever read (InversionResult.unstable_part)
        sums: list[float] = []
        with pass_errstate(True):
            stable, unstable, output = plan.run(ua, chunk, keep_unstable=False, output_sum=sums,
                                                keep_stable=False)
        written_sum = sums[0]
        finite = math.isfinite(written_sum)
        fingerprint = None
    # a finite sum of the output (summed while the pass wrote it) proves every sample finite (as
    # in as_signal); only a non-finite one (a bad sample, or an overflow of the sum) needs the
    # element-wise check, of the input first (a bad input sample is named as as_signal names it)
    if not finite:
        check_finite(ua)
        if fingerprint is None:     # an overflowed sum proves nothing about a later input (class doc)
            fingerprint = signal_fingerprint(ua)
    bad = None if finite else ~np.isfinite(output)
    if bad is not None and bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise NonFiniteSignalError(
            f"the inverse overflowed: output sample {i} is {float(output[i])!r} (input peak {float(np.max(np.abs(ua))):.3g}); "
            "scale the signal to the model's units")
    return InversionResult(
        input=ua, output=output, stable_source=stable, output_sum=written_sum, input_fingerprint=fingerprint,
        unstable_source=unstable if unstable is not None else (plan, chunk),
        preview_s=prev_s, preview_samples=n_prev, r0=split.r0,
        auto_preview_s=split.auto_preview_s, dt=dt, split=split, t0=float(t0),
        time_stamps=ta, preview_rule=rule, preview_choice=choice)


@dataclass(frozen=True)
class ChunkedInversionSummary:
    """Summary returned by :func:`invert_to` (the output itself is in ``out``).

    Attributes
    ----------
    n_samples : int
    dt : float
        Sampling interval [s].
    preview_s : float
        Preview used [s] (``inf`` for infinite).
    preview_samples : int or None
    r0 : float
        [1/s]
    chunk_size : int
    """

    n_samples: int
    dt: float
    preview_s: float
    preview_samples: int | None
    r0: float
    chunk_size: int


def invert_to(model: Any, dt: float, u: Any, out: Any, *, preview: Any = "auto",
              improper: str = "error", filter_bandwidth: float | None = None,
              chunk_size: int = DEFAULT_CHUNK) -> ChunkedInversionSummary:
    """Bounded-memory inversion of a long record, reading ``u`` and writing ``out`` by chunks.

    ``u`` and ``out`` may be anything supporting 1-D slicing and slice assignment, e.g.
    ``numpy.memmap`` arrays backed by files: the working memory is ``O(chunk_size +
    preview samples)`` whatever the record length.  The input is read twice (a forward pass
    for the causal part, then a backward pass for the anticausal part) and ``out`` is read
    back once.  Results equal :func:`invert` up to rounding.

    Parameters
    ----------
    model : control.TransferFunction, control.StateSpace, (num, den) or InverseSplit
    dt : float
        Sampling interval [s].
    u : 1-D array-like
        Signal to invert.
    out : 1-D writable array-like, same length
        Receives the reconstruction.
    preview, improper, filter_bandwidth, chunk_size
        As in :func:`invert`.
    """
    dt = sampling_interval(dt)
    split = as_split(model, improper, filter_bandwidth, dt)
    n = len(u)
    if len(out) != n:
        raise InversionError(f"out must have the same length as u ({n}); got {len(out)}")
    if n < 2:
        raise InversionError(f"the signal must have at least 2 samples; got {n}")
    if not (isinstance(chunk_size, int | np.integer) and chunk_size > 0):
        raise InversionError(f"chunk_size must be a positive integer; got {chunk_size!r}")
    n_prev, prev_s = resolve_preview(preview, split, dt, n)
    plan = plan_for(split, dt, n_prev)

    def put_s(c0: int, c1: int, y: np.ndarray, _x: np.ndarray) -> None:
        out[c0:c1] = y

    def add_u(c0: int, c1: int, y: np.ndarray, _x: np.ndarray) -> None:
        out[c0:c1] = np.asarray(out[c0:c1], dtype=float) + y

    plan.forward(u, n, int(chunk_size), put_s, check=True)
    plan.backward(u, n, int(chunk_size), add_u)
    return ChunkedInversionSummary(n_samples=n, dt=dt, preview_s=prev_s, preview_samples=n_prev,
                                   r0=split.r0, chunk_size=int(chunk_size))


def _with_limits(res: InversionResult, limits: Any, what: str, unit: str) -> InversionResult:
    from dataclasses import replace

    from .limits import check_limits

    report = check_limits(res.output, res.dt, limits, t0=float(res.t[0]), what=what, unit=unit)
    return replace(res, limit_report=report)


def decode_sensor(model: Any, t: Any, current: Any, *, limits: Any = None,
                  **kwargs: Any) -> InversionResult:
    """Sensor decoding: recover the stimulus (e.g. tip displacement) from the sensor output.

    ``model`` maps stimulus -> sensor output (seed 000: displacement [mm] -> short-circuit
    current [uA]).  Same code path and keyword arguments as :func:`invert`.  ``limits``
    (:class:`inversion.limits.Limits`, e.g. ``Limits(output_range=(-2, 2))`` in mm) refuses
    or flags a decoded signal outside the range the strip can reach; the peaks are always in
    ``result.limit_report``.
    """
    return _with_limits(invert(model, t, current, **kwargs), limits, "decoded signal", "")


def feedforward(model: Any, t: Any, desired: Any, *, limits: Any = "default", input_unit: str = "V",
                **kwargs: Any) -> InversionResult:
    """Actuator feedforward: the input (e.g. voltage) that makes the output follow ``desired``.

    ``model`` maps actuator input -> output (seed 001: voltage [V] -> tip displacement [mm]).
    Same code path and keyword arguments as :func:`invert`; ``result.output`` is the
    feedforward input.  Build ``desired`` with :mod:`inversion.references` (fade-in and
    fade-out) so that the noncausal inverse does not see a jump to zero at the record's ends.

    Safe by default: the drive is checked against limits and a violation refused
    (:class:`~inversion.limits.LimitError`, naming the first violating sample) or, with
    ``action="warn"``, warned about; ``result.limit_report`` holds the peak voltage and rate and
    the limits checked.

    Parameters
    ----------
    model : control.TransferFunction, control.StateSpace, (num, den) or InverseSplit
        The actuator model G(s), input (voltage) -> output (e.g. tip displacement), s in rad/s.
    t : array_like or float
        Uniform time stamps [s], or the sampling interval [s] (as :func:`invert`).
    desired : array_like
        The output to follow [model output units, e.g. mm].
    limits : "default", None, "off" or Limits
        ``"default"`` (or None, or omitted): ``|V| <=``
        :data:`~inversion.limits.DEFAULT_MAX_VOLTAGE` (3 V, as ``ipmc feedforward``), converted
        to ``input_unit``.  A :class:`~inversion.limits.Limits` is used as given, in the model's
        input unit (e.g. ``Limits(max_voltage=2.5, max_rate=50)``; ``Limits()`` checks nothing
        and only measures the peaks).  ``"off"``: no limit (the peaks are still measured).
        None meant "no limit" before the 3 V default; it now means "not given".
    input_unit : str
        The unit of the model's input, i.e. of ``result.output`` (default ``"V"``).  A transfer
        function carries no unit, so this cannot be inferred: for a surrogate fitted in mV per
        mm (``surrogate.labels["input_unit"]``) pass ``input_unit="mV"`` so that the default
        limit is 3000 mV, not 3 mV.  Only the default limit and the messages use it.
    **kwargs
        As :func:`invert` (``preview``, ``improper``, ...).
    """
    from .limits import Limits, default_drive_limits

    if limits is None or (isinstance(limits, str) and limits == "default"):
        lim: Limits | None = default_drive_limits(input_unit)
    elif isinstance(limits, str) and limits == "off":
        lim = None
    elif isinstance(limits, Limits):
        lim = limits
    else:
        raise InversionError(f"limits={limits!r}: expected 'default' (3 V), 'off' or an inversion.limits.Limits")
    return _with_limits(invert(model, t, desired, **kwargs), lim, "feedforward voltage", input_unit)
