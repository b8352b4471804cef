"""Statistics shared by the benchmark scripts (not collected by pytest)."""

from __future__ import annotations

import math


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score interval of the proportion k/n (95 % for z = 1.96); (nan, nan) for n = 0."""
    if n == 0:
        return float("nan"), float("nan")
    p = k / n
    den = 1 + z * z / n
    c = (p + z * z / (2 * n)) / den
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return c - h, c + h


def wilson_text(k: int, n: int, z: float = 1.96) -> str:
    """``"k/n = P % (95 %: LO-HI %)"``, or ``"n = 0"``."""
    if n == 0:
        return "n = 0"
    lo, hi = wilson(k, n, z)
    return f"{k}/{n} = {100 * k / n:.0f} % (95 %: {100 * max(0.0, lo):.0f}-{100 * min(1.0, hi):.0f} %)"
