"""The plotting package's canvas: new Agg figures (no pyplot state, safe in threads and workers),
colour maps, and the one atomic figure writer.  Shared by the modules of :mod:`scenarios.plots`
(their contract with each other; users call the package's face).  matplotlib is imported when a
figure is drawn, not when the package is imported."""

from __future__ import annotations

from pathlib import Path

__all__ = ["axes_grid", "colormap", "new_figure", "normalize", "save_figure", "scalar_mappable", "temperature_colors"]


def new_figure(*args, figsize=None, **kw):
    """A new ``Figure`` on an Agg canvas and its axes (like ``pyplot.subplots``, without pyplot state).

    Parameters
    ----------
    *args
        Rows and columns, as ``Figure.subplots``.
    figsize : tuple of float or None
        Width and height. [inch]
    **kw
        Passed to ``Figure.subplots`` (``sharex``, ``squeeze``, ...).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig, fig.subplots(*args, **kw)


def axes_grid(axes, rows: int, cols: int, what: str, **figure_kw):
    """The caller's axes as a ``rows`` × ``cols`` object array, and what a ``plot_*`` function
    returns: ``axes`` as given, or a new figure's axes (``new_figure(rows, cols, **figure_kw)``)
    when ``axes`` is None.

    Parameters
    ----------
    axes : Axes, sequence of Axes, 2-D array of Axes or None
        ``rows * cols`` Axes in row-major order (nested or flat), or None.
    rows, cols : int
        The panels' layout.
    what : str
        The panels, in order, for the error message (``"magnitude, phase, residuals"``).
    **figure_kw
        Passed to :func:`new_figure` when ``axes`` is None (``figsize``, ``sharex``, ...).

    Raises
    ------
    ValueError
        When the number of Axes given is not ``rows * cols``.
    """
    import numpy as np

    given = axes
    if axes is None:
        _, given = new_figure(rows, cols, **figure_kw)

    def flat(x):
        return [a for item in x for a in flat(item)] if isinstance(x, (list, tuple, np.ndarray)) else [x]

    items = flat(given)
    if len(items) != rows * cols:
        raise ValueError(f"axes: give {rows * cols} Axes ({what}), got {len(items)}")
    grid = np.empty(len(items), dtype=object)
    grid[:] = items
    return given, grid.reshape(rows, cols)


def colormap(name: str):
    """The matplotlib colour map ``name``.

    Parameters
    ----------
    name : str
        A registered colour map (``"coolwarm"``, ``"viridis"``).
    """
    import matplotlib

    return matplotlib.colormaps[name]


def normalize(vmin, vmax):
    """A linear ``Normalize(vmin, vmax)``.

    Parameters
    ----------
    vmin, vmax : float
        The ends of the colour scale. [the mapped quantity's unit]
    """
    from matplotlib.colors import Normalize

    return Normalize(vmin, vmax)


def scalar_mappable(**kw):
    """A ``ScalarMappable`` (for a colour bar).

    Parameters
    ----------
    **kw
        ``norm`` and ``cmap``.
    """
    from matplotlib.cm import ScalarMappable

    return ScalarMappable(**kw)


def temperature_colors(temperatures_c, cmap: str = "coolwarm", span: float = 1.0) -> dict:
    """``{temperature: colour}``: the temperatures spread over ``span`` of the colour map, coldest
    first (one temperature: the map's start).

    Parameters
    ----------
    temperatures_c : array_like
        The temperatures. [°C]
    cmap : str
        The colour map.
    span : float
        Fraction of the map used. [-]
    """
    import numpy as np

    temps = np.unique(np.asarray(temperatures_c, float))
    cm = colormap(cmap)
    lo, hi = (temps.min(), temps.max()) if temps.size else (0.0, 0.0)
    return {float(t): cm(0.0 if temps.size == 1 else span * (t - lo) / (hi - lo)) for t in temps}


def save_figure(fig, path, dpi: int = 120) -> Path:
    """Write ``fig`` atomically (:func:`physmodel.data.files.atomic_write`) in the format of the
    file name's extension and return its path.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or Path
        The file to write.
    dpi : int
        Resolution. [dots per inch]
    """
    from physmodel.data.files import atomic_write

    path = Path(path)
    return atomic_write(path, lambda fh: fig.savefig(fh, format=path.suffix.lstrip(".") or "png", dpi=dpi), "wb")
