"""Figures of parameter estimates: fitted values with their intervals against their sourced
ranges, and the ``[chain]`` step's a0(T) series (printed vs calibrated).  Data come in as
arguments: nothing here imports a step."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .canvas import new_figure, save_figure


def effect_intervals(rows: list, path, title: str = "") -> Path:
    """Fitted values with 95 % intervals against their sourced range, one panel per parameter.

    ``rows``: dicts with name, value, ci (lo, hi) or None, identifiable, plausible (lo, hi) or None,
    unit; an undetermined parameter is marked so, without its (meaningless) interval."""
    n = max(len(rows), 1)
    fig, axes = new_figure(n, 1, figsize=(7.0, 0.9 * n + 0.8), squeeze=False)
    for ax, r in zip(axes[:, 0], rows):
        v = r["value"]
        pts = [v] + list(r.get("plausible") or [])
        if r.get("identifiable", True) and r.get("ci") is not None and all(np.isfinite(r["ci"])):
            ax.plot(list(r["ci"]), [0, 0], "-", color="C0", lw=3)
            pts += list(r["ci"])
        else:
            ax.text(0.99, 0.5, "undetermined", transform=ax.transAxes, ha="right", va="center", fontsize=7, color="C3")
        if r.get("plausible") is not None:
            ax.axvspan(*r["plausible"], color="C2", alpha=0.25)
        ax.plot([v], [0], "o", color="C0")
        pos = [abs(x) for x in pts if x != 0 and math.isfinite(x)]
        if all(x > 0 for x in pts) and pos and max(pos) / min(pos) > 30:
            ax.set_xscale("log")
        ax.set_yticks([])
        ax.set_ylabel(r["name"], rotation=0, ha="right", va="center", fontsize=8)
        ax.tick_params(axis="x", labelsize=7)
        ax.set_xlabel(r.get("unit", ""), fontsize=7, labelpad=0)
    if title:
        axes[0, 0].set_title(title + " (green: sourced range; bar: 95 % interval)", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def a0_series(data, fits: dict, path, printed) -> Path:
    """Write printed a0(T) (polynomial and its data points with ±σ of ln a0) against each
    calibration's model a0(T) (solid: calibrated laws; dotted: the set's default laws)
    [1e10 rad⁴/s⁴] vs T [°C].

    Parameters
    ----------
    data : A0Series
        The a0 data (:class:`~scenarios.steps_chain_temperature.A0Series`: ``temperatures_c`` [°C],
        ``a0`` [rad⁴/s⁴], ``sigma_ln`` [-]).
    fits : dict
        ``{label: {"a0_dense": (T [°C], calibrated a0, default-law a0 [rad⁴/s⁴])}}``.
    path : str or Path
        The figure file.
    printed : tuple of array_like
        ``(T, a0)``: the printed polynomial on a dense grid. [°C, rad⁴/s⁴]
    """
    fig, ax = new_figure(1, 1, figsize=(7.0, 4.6))
    t, a0_printed = (np.asarray(v, float) for v in printed)
    ax.plot(t, a0_printed / 1e10, color="k", lw=2.5, label="printed a0(T) polynomial")
    a, s = data.a0 / 1e10, data.sigma_ln
    ax.errorbar(data.temperatures_c, a, yerr=[a * (1 - np.exp(-s)), a * (np.exp(s) - 1)], fmt="o", color="k",
                capsize=3, label="data (fit temperatures, ±σ)")
    for i, (label, v) in enumerate(fits.items()):
        tt, cal, dflt = v["a0_dense"]
        ax.plot(tt, np.asarray(cal) / 1e10, color=f"C{i}", label=f"{label}: calibrated")
        ax.plot(tt, np.asarray(dflt) / 1e10, color=f"C{i}", ls=":", lw=1)
    ax.set_xlabel("temperature [°C]")
    ax.set_ylabel("a0 [1e10 rad⁴/s⁴]")
    ax.set_title("a0(T) of the 4/4 equation-error fit: printed vs physics + chain (dotted: default laws)",
                 fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return save_figure(fig, path)


