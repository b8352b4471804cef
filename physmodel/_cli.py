"""Parsing shared by the command-line plugins (``ipmc calibrate``, ``ipmc diagnose``, ``ipmc sweep`` ...)."""

from __future__ import annotations

from .errors import ParameterError


def parse_assignments(items, option: str = "--param") -> dict[str, float]:
    """``["W=2e-3", "xi=0.2"]`` → ``{"W": 0.002, "xi": 0.2}``; a clear error naming ``option`` otherwise."""
    out: dict[str, float] = {}
    for item in items or []:
        if "=" not in item:
            raise ParameterError(f"{option} expects NAME=VALUE (SI units), got {item!r}")
        k, v = item.split("=", 1)
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise ParameterError(f"{option} {k.strip()}: {v!r} is not a number") from None
    return out
