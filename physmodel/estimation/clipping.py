"""Clipping and saturation of a sampled channel: samples held at a rail.

A converter or amplifier that saturates holds its output at a rail: the extreme value of the record
is then repeated far more often than the values just inside it.  An unclipped smooth peak is not:
near a maximum a signal spends a time ∝ √δ within δ of it, so on a quantised record the top code
holds about 1/(√2 − 1) ≈ 2.4 times the samples of the next code down (and a continuous-valued record
attains its maximum once).  :func:`detect_clipping` therefore flags an extreme value held by at least
``min_samples`` samples and by more than ``ratio`` (default 8) times as many samples as the next
distinct value inside it, on either side, and reports the fraction of samples at the rail(s).

What it does not see: a rail followed by noise added after the clip (no repeated values), and a
soft (gradual) saturation; both distort without repeating a value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import IPMCError

#: Default: a record with more than this fraction of clipped samples on any channel is refused.
MAX_CLIPPED_FRACTION = 0.01


@dataclass(frozen=True)
class Clipping:
    """Samples of one channel held at its rails.

    Attributes
    ----------
    channel : str      channel name
    fraction : float   clipped samples / all samples (both rails)
    samples : int      clipped samples
    high, low : float or None   the rail values found (None: that side is not clipped), in the
        channel's unit
    """

    channel: str
    fraction: float
    samples: int
    high: float | None
    low: float | None

    @property
    def clipped(self) -> bool:
        """True when a rail was found."""
        return self.samples > 0

    def describe(self) -> str:
        """One line naming the channel, its rail(s) and the fraction of samples held there."""
        if self.high is not None and self.high == self.low:
            return f"{self.channel}: constant (every sample is {self.high:.6g})"
        rails = " and ".join(f"{w} rail {v:.6g}" for w, v in (("upper", self.high), ("lower", self.low))
                             if v is not None)
        return f"{self.channel}: {self.fraction:.2%} of samples ({self.samples}) held at the {rails} (clipped)"


def _rail(sorted_x: np.ndarray, ratio: float, min_samples: int) -> tuple[float | None, int]:
    """(rail value, samples at it) at the start of ``sorted_x`` (the extreme first), or (None, 0)."""
    v0 = sorted_x[0]
    n0 = int(np.searchsorted(sorted_x != v0, True)) if sorted_x[-1] != v0 else sorted_x.size
    if n0 < min_samples:
        return None, 0
    rest = sorted_x[n0:]
    n1 = int(np.searchsorted(rest != rest[0], True)) if rest.size and rest[-1] != rest[0] else rest.size
    if n0 > ratio * n1:
        return float(v0), n0
    return None, 0


def detect_clipping(x, channel: str = "signal", *, ratio: float = 8.0, min_samples: int = 4) -> Clipping:
    """Samples held at the extreme values of ``x`` (see the module doc).

    Parameters
    ----------
    x : (n,) array_like
        Samples of one channel (any unit).
    channel : str
        Name used in the report.
    ratio : float
        An extreme value is a rail when it holds more than ``ratio`` times the samples of the next
        distinct value inside it.
    min_samples : int
        And at least this many samples.
    """
    v = np.asarray(x, dtype=float).ravel()
    if v.size == 0:
        raise IPMCError(f"{channel}: no samples")
    if not (ratio >= 1 and min_samples >= 2):
        raise IPMCError(f"ratio={ratio!r} must be >= 1 and min_samples={min_samples!r} >= 2")
    # only the extremes matter: the smallest and largest few percent, found without a full sort
    k = min(v.size, max(64, v.size // 20))
    hi_part = np.sort(np.partition(v, v.size - k)[v.size - k:])[::-1] if k < v.size else np.sort(v)[::-1]
    lo_part = np.sort(np.partition(v, k - 1)[:k]) if k < v.size else np.sort(v)
    if hi_part[0] == lo_part[0]:
        return Clipping(channel, 1.0, v.size, float(hi_part[0]), float(hi_part[0]))   # constant: all one value
    high, n_hi = _rail(hi_part, ratio, min_samples)
    low, n_lo = _rail(lo_part, ratio, min_samples)
    if n_hi == k or n_lo == k:                 # a rail fills the whole partition: count it exactly
        n_hi = int(np.count_nonzero(v == high)) if high is not None else 0
        n_lo = int(np.count_nonzero(v == low)) if low is not None else 0
    return Clipping(channel, (n_hi + n_lo) / v.size, n_hi + n_lo, high, low)


def check_clipping(channels: dict, max_clipped_fraction: float | None = None) -> list[str]:
    """Warnings for the clipped channels of ``{name: samples}``; an :class:`IPMCError` naming them
    when one holds more than ``max_clipped_fraction`` of its samples at a rail.

    Parameters
    ----------
    channels : dict
        Channel name → (n,) samples.
    max_clipped_fraction : float or None
        Largest clipped fraction accepted (default :data:`MAX_CLIPPED_FRACTION`; 1 only warns).
    """
    limit = MAX_CLIPPED_FRACTION if max_clipped_fraction is None else float(max_clipped_fraction)
    if not 0 <= limit <= 1:
        raise IPMCError(f"max_clipped_fraction={max_clipped_fraction!r} must lie in [0, 1]")
    clips = [detect_clipping(x, name) for name, x in channels.items()]
    bad = [c for c in clips if c.clipped and c.fraction > limit]
    if bad:
        raise IPMCError("clipped: " + "; ".join(c.describe() for c in bad) + f" — more than max_clipped_fraction="
                        f"{limit:g}; the estimate would be biased (reduce the drive or widen the input range)")
    return ["clipped: " + c.describe() for c in clips if c.clipped]
