"""Signals against time: a record's input and output (:func:`plot_time`, :func:`traces`), a
reference and what was achieved (:func:`tracking`), an inversion's reconstruction, a feedforward
checked on the physics; and plain curves y(x)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .canvas import new_figure, save_figure

__all__ = ["curves", "feedforward_check", "inversion_traces", "plot_time", "traces", "tracking"]


def plot_time(ts, ax=None, *, output_scale: float = 1.0, output_label: str | None = None, **line_kw):
    """Input and output of a time record on the given axes; returns ``ax``.

    Parameters
    ----------
    ts : TimeSeries
        A :class:`~physmodel.data.timesim.TimeSeries` (``t`` [s], ``input``, ``output`` and, when
        simulated, ``clean_output``, with their names and units).
    ax : Axes, pair of Axes or None
        ``(input, output)`` axes, or one Axes (output only); None: a new figure (its axes returned).
    output_scale : float
        Factor applied to the output (e.g. 1e3 for m → mm). [-]
    output_label : str or None
        The output axis label (default its name and unit).
    **line_kw
        Passed to ``Axes.plot`` (default ``lw=0.8``).

    Returns
    -------
    Axes or pair of Axes
        ``ax`` as given (the new pair when None).
    """
    if ax is None:
        _, ax = new_figure(2, 1, sharex=True, figsize=(7, 5))
    pair = isinstance(ax, (tuple, list, np.ndarray))
    if pair and len(ax) != 2:
        raise ValueError(f"ax: give one Axes (output only) or two (input, output), got {len(ax)}")
    a1, a2 = (ax[0], ax[1]) if pair else (None, ax)
    line_kw.setdefault("lw", 0.8)
    if a1 is not None:
        a1.plot(ts.t, ts.input, **line_kw)
        a1.set_ylabel(f"{ts.input_name} [{ts.input_unit}]")
    a2.plot(ts.t, ts.output * output_scale, label="recorded", **line_kw)
    if ts.clean_output is not None and not np.array_equal(ts.clean_output, ts.output):
        a2.plot(ts.t, ts.clean_output * output_scale, label="noise-free", **line_kw)
        a2.legend(fontsize=8)
    a2.set_ylabel(output_label or f"{ts.output_name} [{ts.output_unit}]")
    a2.set_xlabel("time [s]")
    for a in (a1, a2):
        if a is not None:
            a.grid(True, alpha=0.3)
    return ax


def traces(ts, path, title: str = "", output_scale: float = 1.0, output_label: str | None = None) -> Path:
    """Write the input and output of a :class:`~physmodel.data.timesim.TimeSeries` (:func:`plot_time`).

    Parameters
    ----------
    ts : TimeSeries
        The record.
    path : str or Path
        The figure file.
    title : str
        Title.
    output_scale : float
        Factor applied to the output. [-]
    output_label : str or None
        The output axis label.
    """
    fig, (a1, a2) = new_figure(2, 1, sharex=True, figsize=(7, 5))
    plot_time(ts, (a1, a2), output_scale=output_scale, output_label=output_label)
    a1.set_title(title)
    fig.tight_layout()
    return save_figure(fig, path)


def curves(x, ys: dict, path, xlabel: str, ylabel: str, title: str = "", logx: bool = True) -> Path:
    """Several curves y(x) on one axis (e.g. model orders)."""
    fig, ax = new_figure(figsize=(7, 4))
    for lab, y in ys.items():
        (ax.semilogx if logx else ax.plot)(x, y, label=lab)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    return save_figure(fig, path)


def tracking(t, reference, achieved, path, title: str = "", unit: str = "mm",
             labels=("reference", "achieved"), window=None) -> Path:
    """Reference and achieved signals (top) and their error (bottom); ``window`` shades the
    interval over which the error bound is taken."""
    fig, (a1, a2) = new_figure(2, 1, sharex=True, figsize=(7, 5))
    a1.plot(t, reference, lw=1.0, label=labels[0])
    a1.plot(t, achieved, lw=0.8, ls="--", label=labels[1])
    a1.set_ylabel(f"[{unit}]")
    a1.legend(fontsize=8)
    a2.plot(t, np.asarray(achieved) - np.asarray(reference), lw=0.8, color="C3")
    a2.set_ylabel(f"error [{unit}]")
    a2.set_xlabel("time [s]")
    if window is not None:
        for a in (a1, a2):
            a.axvspan(*window, color="0.9", zorder=0)
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
    a1.set_title(title)
    fig.tight_layout()
    return save_figure(fig, path)


def inversion_traces(path: str, t, u, y, ucol: str,
          ref, refcol, title: str) -> Path:
    """Input, reconstruction and (with a reference) its error against time."""
    rows = 3 if ref is not None else 2
    fig, axes = new_figure(rows, 1, sharex=True, figsize=(8, 2.4 * rows))
    axes[0].plot(t, u, lw=0.8)
    axes[0].set_ylabel(ucol)
    axes[0].set_title(title)
    axes[1].plot(t, y, lw=0.8, label="reconstruction")
    if ref is not None:
        axes[1].plot(t, ref, lw=0.8, ls="--", label=refcol)
        axes[2].plot(t, y - ref, lw=0.8, color="C3")
        axes[2].set_ylabel("error")
    axes[1].set_ylabel("reconstruction")
    axes[1].legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def feedforward_check(t, reference, predicted, voltage, path, *, unit: str = "mm", title: str = "",
                      max_voltage: float | None = None, body=None) -> Path:
    """Three stacked panels over time [s]: reference and predicted tip [unit], the tracking error
    ``predicted - reference`` [unit], and the feedforward voltage [V] with ``±max_voltage``
    dashed.  ``body`` (bool mask) shades the unfaded part of the reference."""
    t = np.asarray(t, dtype=float)
    fig, (a1, a2, a3) = new_figure(3, 1, sharex=True, figsize=(7, 7))
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
    return save_figure(fig, path)
