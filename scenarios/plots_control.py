"""Figures of the control path (to be folded into :mod:`scenarios.plots`): a feedforward checked on
the physics — reference, predicted tip, tracking error and voltage with its limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .plots import _save, _subplots

__all__ = ["feedforward_check"]


def feedforward_check(t, reference, predicted, voltage, path, *, unit: str = "mm", title: str = "",
                      max_voltage: float | None = None, body=None) -> Path:
    """Three stacked panels over time [s]: reference and predicted tip [unit], the tracking error
    ``predicted - reference`` [unit], and the feedforward voltage [V] with ``±max_voltage``
    dashed.  ``body`` (bool mask) shades the unfaded part of the reference."""
    t = np.asarray(t, dtype=float)
    fig, (a1, a2, a3) = _subplots(3, 1, sharex=True, figsize=(7, 7))
    a1.plot(t, reference, lw=1.0, label="reference")
    a1.plot(t, predicted, lw=0.8, ls="--", label="predicted tip (physics)")
    a1.set_ylabel(f"tip [{unit}]")
    a1.legend(fontsize=8)
    err = np.asarray(predicted) - np.asarray(reference)
    a2.plot(t, err, lw=0.8, color="C3")
    a2.set_ylabel(f"error [{unit}]")
    a3.plot(t, voltage, lw=0.8, color="C2")
    a3.set_ylabel("voltage [V]")
    a3.set_xlabel("time [s]")
    if max_voltage is not None:
        for sgn in (1, -1):
            a3.axhline(sgn * max_voltage, color="k", ls=":", lw=0.8)
    if body is not None and np.any(body):
        tb = t[np.asarray(body, bool)]
        for a in (a1, a2, a3):
            a.axvspan(tb[0], tb[-1], color="0.93", zorder=0)
    for a in (a1, a2, a3):
        a.grid(True, alpha=0.3)
    a1.set_title(title or "feedforward checked on the physics")
    fig.tight_layout()
    return _save(fig, path)
