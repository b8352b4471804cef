"""Exceptions raised by :mod:`physmodel`.

Every error names the offending value and what was expected.
"""

from __future__ import annotations


class IPMCError(ValueError):
    """Base class: bad input to an IPMC model (a ``ValueError``)."""


class ParameterError(IPMCError):
    """A parameter value is outside its physical domain."""


class TemperatureRangeError(IPMCError):
    """A temperature lies outside the validity range of a temperature law."""


class NotConvergedError(IPMCError, RuntimeError):
    """An optimiser did not converge (also a ``RuntimeError``); the command line exits 3, not 2."""


class DataFormatError(IPMCError):
    """A data file (CSV/NPZ/MAT) is malformed; the message names the line and the problem."""
