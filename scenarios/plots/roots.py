"""Poles and zeros: a scheduled surrogate's across temperature (a locus coloured by °C,
:func:`plot_pole_zero_locus`, or their real and imaginary parts against °C,
:func:`plot_poles_zeros_vs_temperature`) and pole-zero maps side by side
(:func:`plot_pole_zero_maps`).  The ``plot_*`` functions draw on the ``Axes`` they are given and
return them; the writers make a figure with them and write it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from physmodel.errors import IPMCError

from .canvas import axes_grid, colormap, new_figure, normalize, save_figure, scalar_mappable

__all__ = ["plot_pole_zero_locus", "plot_pole_zero_maps", "plot_poles_zeros_vs_temperature", "pole_zero_locus",
           "pole_zero_maps", "save_poles_zeros_vs_temperature"]


def plot_pole_zero_locus(model, temperatures_c, ax=None, *, colorbar: bool = True):
    """Poles (x) and zeros (o) of a scheduled surrogate across temperature on the given axes,
    coloured by temperature (the ``coolwarm`` map), the real axis symlog; returns ``ax``.

    Parameters
    ----------
    model : RationalModel
        The surrogate (``poles(T)`` and ``zeros(T)``, extrapolated outside its range).
    temperatures_c : array_like
        Where to evaluate its roots. [°C]
    ax : Axes or None
        Where to draw; None: a new figure (its axes returned).
    colorbar : bool
        Add a temperature colour bar beside ``ax`` (taking room from it, as ``Figure.colorbar``).

    Returns
    -------
    Axes
        ``ax`` as given (the new one when None).  Roots are in rad/s; the title is left to the caller.
    """
    temps = np.asarray(temperatures_c, float)
    if ax is None:
        _, ax = new_figure(figsize=(7, 5))
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
    if colorbar:
        ax.figure.colorbar(scalar_mappable(norm=norm, cmap=cmap), ax=ax, label="temperature [°C]")
    return ax


def pole_zero_locus(model, temperatures_c, path, title: str = "") -> Path:
    """Write :func:`plot_pole_zero_locus`'s figure.

    Parameters
    ----------
    model : RationalModel
        The scheduled surrogate.
    temperatures_c : array_like
        Where to evaluate its roots. [°C]
    path : str or Path
        The figure file.
    title : str
        Title (default "poles (x) and zeros (o) vs temperature").
    """
    fig, ax = new_figure(figsize=(7, 5))
    plot_pole_zero_locus(model, temperatures_c, ax)
    ax.set_title(title or "poles (x) and zeros (o) vs temperature")
    fig.tight_layout()
    return save_figure(fig, path)


def plot_poles_zeros_vs_temperature(model, axes=None, *, per_temperature_models=None, n_temperatures: int = 121):
    """Real and imaginary parts of a scheduled surrogate's poles and zeros against temperature on
    the given axes, with the per-temperature fits' roots as crosses when given; returns ``axes``.

    Parameters
    ----------
    model : RationalModel
        A scheduled surrogate, evaluated on ``n_temperatures`` points over its range.
    axes : 2 × 2 Axes or None
        ``((poles real, zeros real), (poles imaginary, zeros imaginary))``, nested or flat in that
        order; None: a new figure (its axes returned).
    per_temperature_models : dict or None
        ``{temperature [°C]: model with poles() and zeros()}`` (a fit's ``per_temperature_models``).
    n_temperatures : int
        Points of the temperature grid.

    Returns
    -------
    Axes array
        ``axes`` as given (the new 2 × 2 array when None).  Roots in rad/s against °C; the legend
        (``scheduled model``, ``per-temperature fits``) is left to the caller.

    Raises
    ------
    IPMCError
        When the model is not scheduled.
    """
    if not model.is_scheduled:
        raise IPMCError("pole/zero-vs-temperature plots need a scheduled model")
    ret, axes = axes_grid(axes, 2, 2, "poles real, zeros real, poles imaginary, zeros imaginary",
                          sharex=True, figsize=(8.0, 6.0))
    lo, hi = model.temperature_range_c
    grid = np.linspace(lo, hi, n_temperatures)
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
    return ret


def save_poles_zeros_vs_temperature(model, path, per_temperature_models=None,
                                    n_temperatures: int = 121) -> None:
    """Write :func:`plot_poles_zeros_vs_temperature`'s figure with its legend.

    Parameters
    ----------
    model : RationalModel
        A scheduled surrogate.
    path : str or Path
        The figure file.
    per_temperature_models : dict or None
        ``{temperature [°C]: model}`` drawn as crosses.
    n_temperatures : int
        Points of the temperature grid.
    """
    fig, axes = new_figure(2, 2, sharex=True, figsize=(8.0, 6.0))
    plot_poles_zeros_vs_temperature(model, axes, per_temperature_models=per_temperature_models,
                                    n_temperatures=n_temperatures)
    axes[0, 0].legend(loc="best", fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def plot_pole_zero_maps(models: dict, axes=None):
    """One pole-zero map per model on the given axes: poles (x), zeros (o), the axes through the
    origin, and each panel titled with its label and its count of right-half-plane zeros; returns
    ``axes``.

    Parameters
    ----------
    models : dict
        ``{label: (zeros, poles)}``, complex roots in rad/s.
    axes : Axes, sequence of Axes or None
        One Axes per model, in the dict's order (a single Axes for a single model); None: a new
        figure, one row (its 1 × n axes returned).

    Returns
    -------
    Axes or Axes array
        ``axes`` as given (the new array when None); the legend is left to the caller.
    """
    n = len(models)
    ret, grid = axes_grid(axes, 1, n, f"one per model: {', '.join(map(str, models))}",
                          figsize=(3.6 * n, 3.8), squeeze=False)
    for ax, (label, (z, p)) in zip(grid[0], models.items()):
        z, p = np.asarray(z, complex), np.asarray(p, complex)
        ax.plot(p.real, p.imag, "x", ms=8, mew=2, color="C3", label="poles")
        ax.plot(z.real, z.imag, "o", ms=7, mfc="none", mew=1.5, color="C0", label="zeros")
        ax.axvline(0.0, color="k", lw=0.8)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_title(f"{label}\n{int(np.sum(z.real > 0))} RHP zero(s)", fontsize=9)
        ax.set_xlabel("Re s [rad/s]")
        ax.grid(True, alpha=0.3)
    grid[0, 0].set_ylabel("Im s [rad/s]")
    return ret


def pole_zero_maps(models: dict, path, title: str = "") -> Path:
    """Write :func:`plot_pole_zero_maps`'s figure (one row) with a legend and ``title``.

    Parameters
    ----------
    models : dict
        ``{label: (zeros, poles)}``, complex roots in rad/s.
    path : str or Path
        The figure file.
    title : str
        The figure's title.
    """
    fig, axes = new_figure(1, len(models), figsize=(3.6 * len(models), 3.8), squeeze=False)
    plot_pole_zero_maps(models, axes)
    axes[0][0].legend(fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)
