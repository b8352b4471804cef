"""Stable (noncausal) inversion of non-minimum-phase SISO models, for IPMC sensor decoding
and actuator feedforward, with finite preview, streaming and time-varying temperature.

The inverse ``1/G`` of a proper model is split into a causal stable part (run forward in
time), an anticausal part (run backward in time) and, for strictly proper models, a
polynomial part (Devasia–Chen–Paden stable inversion, as used by seed papers 000 and 001).
The anticausal part can be truncated to a finite preview ``T_p`` (Zou–Devasia).  The default
``preview="auto"`` chooses the shortest ``T_p`` whose bound on the truncation error is below
``preview_tol`` (1e-3) of the full inverse, for the signal at hand (batch: the discarded kernel's
l1 norm times the signal's peak; the exact error is reported) or for every sinusoid up to the Nyquist
frequency (streaming, bounded-memory, scheduled); the seed-000 rule ``T_p* = 4/r0`` (``r0`` the
real part of the least unstable inverse pole) stays available as ``preview="4/r0"``.  Limits
(:mod:`inversion.limits`) refuse or flag feedforward voltages and rates, and decoded ranges, that
a real strip cannot take; :mod:`inversion.references` builds faded references.

Public API
----------
Batch inversion (:mod:`inversion.batch`)
    invert(model, t, u, *, preview="auto", preview_tol=1e-3, improper="error", ...)
        -> InversionResult (preview_s, preview_rule, preview_choice, truncation_error/_bound)
    decode_sensor(model, t, current, **kw)      sensor output -> stimulus (same code path)
    feedforward(model, t, desired, **kw)        desired output -> actuator input (same path)
    invert_to(model, dt, u, out, *, preview=..., chunk_size=...)
        bounded-memory inversion of long (e.g. memory-mapped) records
    InversionResult, ChunkedInversionSummary
    resolve_preview(preview, split_or_auto, dt, n_samples=None) -> (samples | None, seconds)
    choose_preview(split, dt, u, tol=1e-3, norm="linf") -> PreviewChoice   (the "auto" rule)
    sampling_interval(t) -> dt (checks uniform sampling)

Automatic preview (:mod:`inversion.preview`)
    choose_preview(split, dt, u, tol=1e-3, norm="linf") -> PreviewChoice (samples, seconds,
        relative_error, max_error, tail_bound, error_bound, reference_bound, rule_4_over_r0_s);
    truncation_error(split, dt, u, N) (exact e_N); discrete_tail_l1(split, dt, n) (the bound)

Model split (:mod:`inversion.split`)
    split_inverse(model, *, improper="error", filter_bandwidth=None) -> InverseSplit
    InverseSplit (feedthrough, derivative_coefficients, A_s/B_s/C_s, A_u/B_u/C_u, r0,
        auto_preview_s (4/r0), frequency_response(), stable_tf(), unstable_tf(), l1_norms(),
        tail_l1_norm(T), truncation_response(T, omega))
    frequency_preview(split, tol, omega_max=...) -> (seconds, bound)   signal-independent rule
    model_coefficients(model) -> (num, den)

Streaming (:mod:`inversion.streaming`)
    StreamingInverter(model, dt, preview="auto", ...)  .push(chunk) / .flush() / .reset(),
        output delayed by exactly ``delay_samples = round(T_p/dt)``

Time-varying temperature (:mod:`inversion.scheduled`)
    invert_scheduled(model_at, t, u, temperature, *, preview="auto", grid_step=1.0, ...)
        -> ScheduledInversionResult
    invert_scheduled_to(model_at, dt, u, temperature, out, ...)   bounded memory
    ScheduledStreamingInverter(model_at, dt, temperature_range, preview="auto", ...)
    temperature_grid(t_min, t_max, step)

Errors (:mod:`inversion._errors`, all ``ValueError`` subclasses)
    InversionError, NonHyperbolicModelError, ImproperInverseError, NonUniformSamplingError,
    NonFiniteSignalError, PreviewError; ZeroAtInfinityWarning (a zero the sampling cannot
    represent was treated as at infinity: ``split_inverse(..., dt=)``, ``result.notes``)

Examples and toy models (:mod:`inversion.examples`)
    seed000_sensor_35c(form="coefficients" | "zeros"), toy_scheduled_sensor(T),
    toy_actuator(), released_cantilever(t, ...)

Limits (:mod:`inversion.limits`)
    Limits(max_voltage=None, max_rate=None, output_range=None, action="error"|"warn")
    check_limits(signal, t, limits, what=...) -> LimitReport (first violating sample);
    LimitError, LimitWarning; DEFAULT_MAX_VOLTAGE (3 V): feedforward(...) refuses a drive beyond it
    unless told otherwise (limits=Limits(max_voltage=2.5, max_rate=50), or limits="off");
    input_unit="mV" for a model whose input is in mV.  invert() checks no limit.

References (:mod:`inversion.references`)
    sine, multitone, smoothed_steps, from_file, fade -> Reference (t, y, fade windows)

Units: SI inside (s, rad/s, 1/s); signals keep the units of the model (seed 000: mm and uA).
"""

from . import references
from ._errors import (
    ImproperInverseError,
    InversionError,
    NonFiniteSignalError,
    NonHyperbolicModelError,
    NonUniformSamplingError,
    PreviewError,
    ZeroAtInfinityWarning,
)
from .batch import (
    ChunkedInversionSummary,
    InversionResult,
    PreviewChoice,
    choose_preview,
    decode_sensor,
    feedforward,
    invert,
    invert_to,
    resolve_preview,
    sampling_interval,
)
from .limits import DEFAULT_MAX_VOLTAGE, LimitError, Limits, LimitWarning, check_limits
from .preview import DEFAULT_PREVIEW_TOL, frequency_preview
from .scheduled import (
    ScheduledInversionResult,
    ScheduledStreamingInverter,
    invert_scheduled,
    invert_scheduled_to,
    temperature_grid,
)
from .split import InverseSplit, model_coefficients, split_inverse
from .streaming import StreamingInverter

__all__ = [
    "DEFAULT_MAX_VOLTAGE",
    "DEFAULT_PREVIEW_TOL",
    "LimitError",
    "LimitWarning",
    "Limits",
    "check_limits",
    "references",
    "PreviewChoice",
    "choose_preview",
    "frequency_preview",
    "ChunkedInversionSummary",
    "ImproperInverseError",
    "InverseSplit",
    "InversionError",
    "InversionResult",
    "NonFiniteSignalError",
    "NonHyperbolicModelError",
    "NonUniformSamplingError",
    "PreviewError",
    "ZeroAtInfinityWarning",
    "ScheduledInversionResult",
    "ScheduledStreamingInverter",
    "StreamingInverter",
    "decode_sensor",
    "feedforward",
    "invert",
    "invert_scheduled",
    "invert_scheduled_to",
    "invert_to",
    "model_coefficients",
    "resolve_preview",
    "sampling_interval",
    "split_inverse",
    "temperature_grid",
]
