"""Figures of the ``[chain]`` step (seed 000's printed model vs physics alone vs physics + chain).

Written with :mod:`scenarios.plots`' ``_subplots``/``_save`` helpers (Agg ``Figure`` objects,
atomic writes); to be folded into :mod:`scenarios.plots`.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .plots import _save, _subplots


def bode_overlay(frequency_hz, curves: dict, path, band_hz=None, title: str = "") -> Path:
    """Magnitude [dB] and phase [deg] of several complex responses on one grid.

    ``curves``: {label: (response, style dict)}; ``band_hz``: (lo, hi) shaded as the data band."""
    f = np.asarray(frequency_hz, float)
    fig, (am, ap) = _subplots(2, 1, sharex=True, figsize=(7.5, 6.5))
    for label, (G, style) in curves.items():
        G = np.asarray(G, complex)
        am.semilogx(f, 20 * np.log10(np.abs(G)), label=label, **style)
        ap.semilogx(f, np.degrees(np.unwrap(np.angle(G))), **style)
    for ax in (am, ap):
        if band_hz is not None:
            ax.axvspan(*band_hz, color="0.92", zorder=0)
        ax.grid(True, which="both", alpha=0.3)
    am.set_ylabel("|G| [dB re 1 µA/mm]")
    ap.set_ylabel("∠G [deg]")
    ap.set_xlabel("frequency [Hz]")
    am.legend(fontsize=8)
    if title:
        am.set_title(title, fontsize=10)
    return _save(fig, path)


def pole_zero_maps(models: dict, path, title: str = "") -> Path:
    """One pole-zero map [rad/s] per model: {label: (zeros, poles)}; right-half-plane zeros counted."""
    n = len(models)
    fig, axes = _subplots(1, n, figsize=(3.6 * n, 3.8), squeeze=False)
    for ax, (label, (z, p)) in zip(axes[0], models.items()):
        z, p = np.asarray(z, complex), np.asarray(p, complex)
        ax.plot(p.real, p.imag, "x", ms=8, mew=2, color="C3", label="poles")
        ax.plot(z.real, z.imag, "o", ms=7, mfc="none", mew=1.5, color="C0", label="zeros")
        ax.axvline(0.0, color="k", lw=0.8)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_title(f"{label}\n{int(np.sum(z.real > 0))} RHP zero(s)", fontsize=9)
        ax.set_xlabel("Re s [rad/s]")
        ax.grid(True, alpha=0.3)
    axes[0][0].set_ylabel("Im s [rad/s]")
    axes[0][0].legend(fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def effect_intervals(rows: list, path, title: str = "") -> Path:
    """Fitted values with 95 % intervals against their sourced range, one panel per parameter.

    ``rows``: dicts with name, value, ci (lo, hi) or None, identifiable, plausible (lo, hi) or None,
    unit; an undetermined parameter is marked so, without its (meaningless) interval."""
    n = max(len(rows), 1)
    fig, axes = _subplots(n, 1, figsize=(7.0, 0.9 * n + 0.8), squeeze=False)
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
    return _save(fig, path)


def a0_series(data, fits: dict, path) -> Path:
    """Printed a0(T) (polynomial and its data points with ±σ of ln a0) against each calibration's model
    a0(T) (solid: calibrated laws; dotted: the set's default laws) [1e10 rad⁴/s⁴] vs T [°C].

    ``data``: :class:`~scenarios.steps_chain_temperature.A0Series`; ``fits``: {label: {"a0_dense": (T,
    calibrated, default)}}."""
    from .steps_chain_temperature import printed_a0

    fig, ax = _subplots(1, 1, figsize=(7.0, 4.6))
    t = np.linspace(20.0, 70.0, 101)
    ax.plot(t, printed_a0(t) / 1e10, color="k", lw=2.5, label="printed a0(T) polynomial")
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
    return _save(fig, path)


__all__ = ["a0_series", "bode_overlay", "effect_intervals", "pole_zero_maps"]
