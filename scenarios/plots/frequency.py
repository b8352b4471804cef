"""Bode plots: of a sweep (its σ as error bars or bands), of a model (physics at temperatures, a
model file with the band its parameter intervals give, a surrogate with the band its covariance
gives), and of a model against data (:func:`plot_compare`).  The ``plot_*`` functions draw on the
``Axes`` they are given and return them; the writers (:func:`bode`, :func:`compare_figure`,
:func:`save_bode`, :func:`bode_overlay`) make a figure with them and write it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .canvas import new_figure, save_figure, temperature_colors

__all__ = ["bode", "bode_overlay", "compare_figure", "plot_bode", "plot_compare", "save_bode"]

#: Styles drawn as markers (data), the others as lines (models).
MARKERS = ("o", ".", "x", "s", "+", "^", "v", "d", "*")


def _axes_pair(ax):
    """(magnitude axes, phase axes or None) from what the caller gave (None: a new figure)."""
    if ax is None:
        _, ax = new_figure(2, 1, sharex=True, figsize=(7, 6))
    if isinstance(ax, (tuple, list, np.ndarray)):
        if len(ax) != 2:
            raise ValueError(f"ax: give one Axes (magnitude only) or two (magnitude, phase), got {len(ax)}")
        return ax, ax[0], ax[1]
    return ax, ax, None


def _phase_offsets(sweep, align) -> dict:
    """Multiples of 360° that put ``sweep``'s phase on ``align``'s branch, per common temperature."""
    if align is None:
        return {}
    out = {}
    ph_s, ph_a = sweep.phase_deg, align.phase_deg
    for t in np.intersect1d(sweep.temperatures(), align.temperatures()):
        ms, ma = sweep.temperature_c == t, align.temperature_c == t
        fs, fa = np.log(sweep.frequency_hz[ms]), np.log(align.frequency_hz[ma])
        at = np.interp(fa, fs, ph_s[ms])
        out[float(t)] = 360.0 * np.round(np.mean(ph_a[ma] - at) / 360.0)
    return out


def plot_bode(source, ax=None, *, temperatures_c=None, frequency_hz=None, like=None, quantity=None,
              band: bool = True, k_sigma: float = 2.0, style: str = "-", label: str = "", colors=None,
              align=None, **line_kw):
    """Bode plot of a sweep or a model on the given axes, one colour per temperature; returns ``ax``.

    Parameters
    ----------
    source : FrequencySweep, ModelFile, RationalModel or FrequencyModel
        A sweep (drawn at its lines; its per-line σ as ±``k_sigma``·σ error bars with a marker
        ``style``, as bands with a line style), or a model evaluated by
        :func:`scenarios.prediction.predict_sweep` (a model file or a surrogate with a
        ±``k_sigma``·σ band from its parameters' uncertainty).
    ax : Axes, pair of Axes or None
        ``(magnitude, phase)`` axes, or one Axes (magnitude only); None: a new figure (its axes
        returned).
    temperatures_c : array_like or None
        Temperatures of a model [°C]; default ``like``'s, else the model's own.
    frequency_hz : array_like or None
        Frequencies of a model [Hz]; default 200 over ``like``'s band.
    like : FrequencySweep or None
        Data whose units (and band and temperatures) a model is drawn in.
    quantity : str or None
        Physics quantity (M, H, I, Z, S) of a model.
    band : bool
        Draw the σ (error bars or band); for a model, compute its band.
    k_sigma : float
        Half-width of the bars or band in σ. [-]
    style : str
        A marker (``"o"``, ``"."``, ``"x"``, ...) or a line style (``"-"``, ``"--"``).
    label : str
        Prefix of the legend entries (``"<label> <T> °C"``).
    colors : dict or callable or None
        ``{temperature: colour}`` or ``f(temperature) -> colour``; default the temperatures spread
        over the ``coolwarm`` map.
    align : FrequencySweep or None
        Draw the phase on this sweep's branch (a multiple of 360° per temperature).
    **line_kw
        Passed to ``Axes.semilogx`` (``lw``, ``ms``, ``alpha``, ...).

    Returns
    -------
    Axes or pair of Axes
        ``ax`` as given (the new pair when None).
    """
    from physmodel.data.sweep import FrequencySweep

    if isinstance(source, FrequencySweep):
        sweep = source
    else:
        from ..prediction import predict_sweep

        sweep = predict_sweep(source, frequency_hz, temperatures_c, like=like, quantity=quantity, uncertainty=band)
    ret, ax_m, ax_p = _axes_pair(ax)
    if colors is None:
        colors = temperature_colors(sweep.temperatures())
    colour = colors if callable(colors) else colors.__getitem__
    offsets = _phase_offsets(sweep, align)
    mag, ph = sweep.magnitude_db, sweep.phase_deg
    bars = band and sweep.magnitude_std_db is not None and sweep.phase_std_deg is not None
    sm = k_sigma * np.asarray(sweep.magnitude_std_db if bars else np.full(mag.shape, np.nan), float)
    sp = k_sigma * np.asarray(sweep.phase_std_deg if bars else np.full(mag.shape, np.nan), float)
    marker = style in MARKERS
    if marker:
        line_kw.setdefault("ms", 3)
    for t in sweep.temperatures():
        m = sweep.temperature_c == t
        f, c = sweep.frequency_hz[m], colour(float(t))
        kw = dict(color=c, label=f"{label}{' ' if label else ''}{t:g} °C", **line_kw)
        phase = ph[m] + offsets.get(float(t), 0.0)
        pairs = [(ax_m, mag[m], sm[m] if bars else None)]
        if ax_p is not None:
            pairs.append((ax_p, phase, sp[m] if bars else None))
        for a, y, err in pairs:
            if err is not None and marker:
                a.errorbar(f, y, yerr=err, fmt=style, elinewidth=0.6, capsize=0, **kw)
                a.set_xscale("log")
                continue
            if err is not None:
                a.fill_between(f, y - err, y + err, color=c, alpha=0.2, lw=0)
            a.semilogx(f, y, style, **kw)
    for a, text in ((ax_m, f"magnitude [dB {sweep.output_unit}/{sweep.input_unit}]"), (ax_p, "phase [deg]")):
        if a is not None:
            if not a.get_ylabel():
                a.set_ylabel(text)
            a.grid(True, which="both", alpha=0.3)
    bottom = ax_p if ax_p is not None else ax_m
    if not bottom.get_xlabel():
        bottom.set_xlabel("frequency [Hz]")
    return ret


def bode(sweeps, path, title: str = "", labels=None, styles=None) -> Path:
    """Write a Bode plot of one or more :class:`~physmodel.data.sweep.FrequencySweep` (one line per
    temperature, colours shared across the sweeps) drawn with :func:`plot_bode`.

    Parameters
    ----------
    sweeps : FrequencySweep or list of FrequencySweep
        Drawn with the given ``styles`` (e.g. data as markers, model as lines), without σ.
    path : str or Path
        The figure file.
    title : str
        Title (default output / input).
    labels : list of str or None
        Legend prefix per sweep.
    styles : list of str or None
        Style per sweep (default lines).
    """
    from physmodel.data.sweep import FrequencySweep

    if isinstance(sweeps, FrequencySweep):
        sweeps = [sweeps]
    labels = labels or [""] * len(sweeps)
    styles = styles or ["-"] * len(sweeps)
    fig, (ax_m, ax_p) = new_figure(2, 1, sharex=True, figsize=(7, 6))
    colors = temperature_colors(np.concatenate([s.temperatures() for s in sweeps]))
    for sw, lab, sty in zip(sweeps, labels, styles):
        plot_bode(sw, (ax_m, ax_p), band=False, style=sty, label=lab, colors=colors)
    sw0 = sweeps[0]
    ax_m.set_ylabel(f"magnitude [dB {sw0.output_unit}/{sw0.input_unit}]")
    ax_m.legend(fontsize=7, ncol=2)
    ax_m.set_title(title or f"{sw0.output_name} / {sw0.input_name}")
    fig.tight_layout()
    return save_figure(fig, path)


def plot_compare(comparison, ax=None, *, points: int = 200, band: bool = True, k_sigma: float = 2.0):
    """A model against data (a :class:`scenarios.comparison.Comparison`) on the given axes: the data
    as markers with ±``k_sigma``·σ bars, the model as lines over the data's band (with its band
    when its parameters carry uncertainty), one colour per temperature, its fit % in the legend.

    Parameters
    ----------
    comparison : Comparison
        What :func:`scenarios.comparison.compare` returned.
    ax : Axes, pair of Axes or None
        ``(magnitude, phase)``, one Axes (magnitude only) or None (a new figure).
    points : int
        Frequencies of the model's lines.
    band : bool
        Draw the data's σ and the model's band.
    k_sigma : float
        Half-width of bars and band in σ. [-]

    Returns
    -------
    Axes or pair of Axes
        ``ax`` as given (the new pair when None).
    """
    from ..prediction import predict_sweep

    data = comparison.data
    ret, ax_m, ax_p = _axes_pair(ax)
    pair = (ax_m, ax_p) if ax_p is not None else ax_m
    colors = temperature_colors(data.temperatures(), "viridis", 0.85)
    fits = {f.temperature_c: f for f in comparison.fits}
    plot_bode(data, pair, band=band, k_sigma=k_sigma, style="o", colors=colors)
    if comparison.model is not None:
        f = np.geomspace(data.frequency_hz.min(), data.frequency_hz.max(), points)
        model = predict_sweep(comparison.model, f, data.temperatures(), like=data, uncertainty=band)
    else:
        model = comparison.predicted
    for line in list(ax_m.get_lines()) + [c for c in ax_m.containers]:
        lab = line.get_label()
        for t, fr in fits.items():
            if lab == f"{t:g} °C":
                line.set_label(f"{t:g} °C: fit {fr.fit_percent:.1f} %" + ("" if fr.adequate else " (MISFIT)"))
    plot_bode(model, pair, band=band, k_sigma=k_sigma, style="-", colors=colors, align=data, label="_model")
    return ret


def compare_figure(comparison, path, title: str = "") -> Path:
    """Write :func:`plot_compare`'s figure.

    Parameters
    ----------
    comparison : Comparison
        What :func:`scenarios.comparison.compare` returned.
    path : str or Path
        The figure file.
    title : str
        Title (default: the model and the verdict).
    """
    fig, (ax_m, ax_p) = new_figure(2, 1, sharex=True, figsize=(7.5, 6.5))
    plot_compare(comparison, (ax_m, ax_p))
    ax_m.legend(fontsize=7, ncol=2)
    banded = len(ax_m.collections) > (0 if comparison.data.magnitude_std_db is None else len(ax_m.containers))
    ax_m.set_title(title or f"data (markers{', ±2σ' if comparison.data.magnitude_std_db is not None else ''}) vs "
                   f"{comparison.model_name} (lines{', ±2σ band' if banded else ''})", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def bode_overlay(frequency_hz, curves: dict, path, band_hz=None, title: str = "") -> Path:
    """Write magnitude [dB] and phase [deg] of several complex responses on one grid.

    Parameters
    ----------
    frequency_hz : array_like
        The grid. [Hz]
    curves : dict
        ``{label: (response, style dict)}``; responses complex on the grid. [µA/mm]
    path : str or Path
        The figure file.
    band_hz : tuple of float or None
        (lo, hi) shaded as the data band. [Hz]
    title : str
        Title.
    """
    f = np.asarray(frequency_hz, float)
    fig, (am, ap) = new_figure(2, 1, sharex=True, figsize=(7.5, 6.5))
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
    return save_figure(fig, path)


def save_bode(model, data, temperature_c, path, title=None) -> None:
    """Write measured vs surrogate magnitude [dB] and phase [deg] at one temperature.

    Parameters
    ----------
    model : RationalModel
        The fitted surrogate.
    data : FrequencyData or FrequencySweep
        The data it was fitted to.
    temperature_c : float or None
        The temperature [°C]; None for data without one.
    path : str or Path
        The figure file.
    title : str or None
        Title.
    """
    d = data if temperature_c is None else data.at_temperature(temperature_c)
    order = np.argsort(d.frequency_hz)
    f = d.frequency_hz[order]
    hd = d.response[order]
    fd = np.geomspace(f.min(), f.max(), 400)
    t_eval = temperature_c if model.is_scheduled else None
    hm = model.frequency_response(fd, t_eval)
    fig, (ax1, ax2) = new_figure(2, 1, sharex=True, figsize=(6.4, 5.2))
    ax1.semilogx(f, 20 * np.log10(np.abs(hd)), "o", ms=3.5, label="data")
    ax1.semilogx(fd, 20 * np.log10(np.abs(hm)), "-", label="model")
    ph_d = np.degrees(np.unwrap(np.angle(hd)))
    ph_m = np.degrees(np.unwrap(np.angle(hm)))
    hm_at_data = model.frequency_response(f, t_eval)
    shift = 360.0 * np.round(np.mean(ph_d - np.degrees(np.unwrap(np.angle(hm_at_data)))) / 360.0)
    ax2.semilogx(f, ph_d, "o", ms=3.5)
    ax2.semilogx(fd, ph_m + shift, "-")
    unit = data.output_unit + "/" + data.input_unit if data.output_unit or data.input_unit else ""
    ax1.set_ylabel(f"magnitude [dB{(' ' + unit) if unit else ''}]")
    ax2.set_ylabel("phase [deg]")
    ax2.set_xlabel("frequency [Hz]")
    ax1.legend(loc="best")
    ax1.grid(True, which="both", alpha=0.3)
    ax2.grid(True, which="both", alpha=0.3)
    if title:
        ax1.set_title(title)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
