"""Exceptions raised by :mod:`inversion`.

Every error is a :class:`physmodel.errors.IPMCError` (the library's one error root, a
:class:`ValueError`); the message always names the offending value and what was expected instead.
"""

from __future__ import annotations

from physmodel.errors import IPMCError

__all__ = [
    "InversionError",
    "NonHyperbolicModelError",
    "ImproperInverseError",
    "NonUniformSamplingError",
    "NonFiniteSignalError",
    "PreviewError",
    "ZeroAtInfinityWarning",
]


class InversionError(IPMCError):
    """Base class of every input error raised by :mod:`inversion`."""


class NonHyperbolicModelError(InversionError):
    """The model has a zero on (or numerically indistinguishable from) the imaginary axis.

    Its inverse then has a pole on the imaginary axis and has no bounded (stable,
    possibly noncausal) realization.
    """


class ImproperInverseError(InversionError):
    """The model is strictly proper, so its inverse is improper, and no handling was chosen."""


class NonUniformSamplingError(InversionError):
    """The time stamps are not uniformly spaced (or not increasing)."""


class NonFiniteSignalError(InversionError):
    """The signal (or temperature trace) contains NaN or infinity."""


class PreviewError(InversionError):
    """The preview time is invalid (negative, NaN, longer than the record, or infinite where
    a finite preview is required)."""


class ZeroAtInfinityWarning(UserWarning):
    """A model zero beyond what the sampling represents was treated as at infinity (the inverse
    is that of the model without it; :mod:`inversion.split`, "Zeros at infinity").  The same
    words are in ``InverseSplit.notes`` and ``InversionResult.notes``."""
