"""Stable (noncausal) inversion of non-minimum-phase SISO models, for IPMC sensor decoding
and actuator feedforward, with finite preview, streaming and time-varying temperature.

The inverse ``1/G`` of a proper model is split into a causal stable part (run forward in
time), an anticausal part (run backward in time) and, for strictly proper models, a
polynomial part (Devasia–Chen–Paden stable inversion, as used by seed papers 000 and 001).
The anticausal part can be truncated to a finite preview ``T_p`` (Zou–Devasia), with the
automatic choice ``T_p* = 4/r0``, ``r0`` the real part of the least unstable inverse pole.

Public API
----------
Batch inversion (:mod:`inversion.batch`)
    invert(model, t, u, *, preview="auto", improper="error", filter_bandwidth=None, ...)
        -> InversionResult
    decode_sensor(model, t, current, **kw)      sensor output -> stimulus (same code path)
    feedforward(model, t, desired, **kw)        desired output -> actuator input (same path)
    invert_to(model, dt, u, out, *, preview=..., chunk_size=...)
        bounded-memory inversion of long (e.g. memory-mapped) records
    InversionResult, ChunkedInversionSummary
    resolve_preview(preview, split_or_auto, dt, n_samples=None) -> (samples | None, seconds)
    sampling_interval(t) -> dt (checks uniform sampling)

Model split (:mod:`inversion.split`)
    split_inverse(model, *, improper="error", filter_bandwidth=None) -> InverseSplit
    InverseSplit (feedthrough, derivative_coefficients, A_s/B_s/C_s, A_u/B_u/C_u, r0,
        auto_preview_s, frequency_response(), stable_tf(), unstable_tf(), l1_norms())
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
    NonFiniteSignalError, PreviewError

Examples and toy models (:mod:`inversion.examples`)
    seed000_sensor_35c(form="coefficients" | "zeros"), toy_scheduled_sensor(T),
    toy_actuator(), released_cantilever(t, ...)

Command line (:mod:`inversion.cli`)
    add_parser(subparsers), run(args) -> exit code — the ``ipmc invert`` subcommand.

Units: SI inside (s, rad/s, 1/s); signals keep the units of the model (seed 000: mm and uA).
"""

from ._errors import (
    ImproperInverseError,
    InversionError,
    NonFiniteSignalError,
    NonHyperbolicModelError,
    NonUniformSamplingError,
    PreviewError,
)
from .batch import (
    ChunkedInversionSummary,
    InversionResult,
    decode_sensor,
    feedforward,
    invert,
    invert_to,
    resolve_preview,
    sampling_interval,
)
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
    "ChunkedInversionSummary",
    "ImproperInverseError",
    "InverseSplit",
    "InversionError",
    "InversionResult",
    "NonFiniteSignalError",
    "NonHyperbolicModelError",
    "NonUniformSamplingError",
    "PreviewError",
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
