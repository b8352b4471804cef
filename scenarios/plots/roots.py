"""Poles and zeros: a scheduled surrogate's across temperature (a locus coloured by °C, or their
real and imaginary parts against °C) and pole-zero maps side by side."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from physmodel.errors import IPMCError

from .canvas import colormap, new_figure, normalize, save_figure, scalar_mappable

__all__ = ["pole_zero_locus", "pole_zero_maps", "save_poles_zeros_vs_temperature"]


def pole_zero_locus(model, temperatures_c, path, title: str = "") -> Path:
    """Poles (x) and zeros (o) of a scheduled surrogate across temperature, coloured by °C [rad/s]."""
    temps = np.asarray(temperatures_c, float)
    fig, ax = new_figure(figsize=(7, 5))
    cmap = colormap("coolwarm")
    norm = normalize(temps.min(), temps.max() if temps.max() > temps.min() else temps.min() + 1)
    for t in temps:
        z, p = model.zeros(t, extrapolate=True), model.poles(t, extrapolate=True)
        c = [cmap(norm(t))]
        ax.scatter(z.real, z.imag, marker="o", facecolors="none", edgecolors=c, s=18)
        ax.scatter(p.real, p.imag, marker="x", c=c, s=18)
    ax.axvline(0, color="k", lw=0.6)
    ax.set_xscale("symlog", linthresh=1.0)
    ax.set_xlabel("real part [rad/s] (symlog)")
    ax.set_ylabel("imaginary part [rad/s]")
    ax.grid(True, alpha=0.3)
    sm = scalar_mappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax, label="temperature [°C]")
    ax.set_title(title or "poles (x) and zeros (o) vs temperature")
    fig.tight_layout()
    return save_figure(fig, path)


def save_poles_zeros_vs_temperature(model, path, per_temperature_models=None,
                                    n_temperatures: int = 121) -> None:
    """Real and imaginary parts of poles and zeros [rad/s] against temperature [°C]."""
    if not model.is_scheduled:
        raise IPMCError("pole/zero-vs-temperature plots need a scheduled model")
    lo, hi = model.temperature_range_c
    grid = np.linspace(lo, hi, n_temperatures)
    fig, axes = new_figure(2, 2, sharex=True, figsize=(8.0, 6.0))
    for col, (name, getter) in enumerate((("poles", model.poles), ("zeros", model.zeros))):
        roots = [getter(t) for t in grid]
        tt = np.repeat(grid, [r.size for r in roots])
        vals = np.concatenate(roots).astype(complex) if roots else np.zeros(0, complex)
        axes[0, col].plot(tt, vals.real, ".", ms=2, label="scheduled model")
        axes[1, col].plot(tt, vals.imag, ".", ms=2)
        if per_temperature_models:
            roots_t = [(t, m.poles() if name == "poles" else m.zeros()) for t, m in per_temperature_models.items()]
            pt = np.concatenate([np.full(r.size, t) for t, r in roots_t])
            pv = np.concatenate([r for _, r in roots_t]).astype(complex)
            axes[0, col].plot(pt, pv.real, "x", ms=5, label="per-temperature fits")
            axes[1, col].plot(pt, pv.imag, "x", ms=5)
        axes[0, col].set_title(name)
        axes[0, col].set_ylabel("real part [rad/s]")
        axes[1, col].set_ylabel("imaginary part [rad/s]")
        axes[1, col].set_xlabel("temperature [°C]")
        for ax in axes[:, col]:
            ax.grid(True, alpha=0.3)
    axes[0, 0].legend(loc="best", fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def pole_zero_maps(models: dict, path, title: str = "") -> Path:
    """One pole-zero map [rad/s] per model: {label: (zeros, poles)}; right-half-plane zeros counted."""
    n = len(models)
    fig, axes = new_figure(1, n, figsize=(3.6 * n, 3.8), squeeze=False)
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
    return save_figure(fig, path)
