"""``ipmc validate`` (kept importable): the implementation is the :mod:`scenarios.validation` package."""

from .validation import *
from .validation import __all__  # noqa: F401
