"""``ipmc validate`` (kept importable): the implementation is the :mod:`scenarios.validation` package."""

from .validation import *  # noqa: F401,F403
from .validation import __all__  # noqa: F401
