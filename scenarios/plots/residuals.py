"""Figures of fits against their data: the calibration overlay with standardised residuals
(:func:`plot_calibration`), data with ±2σ bands against a model's response
(:func:`plot_residual_bode`; the diagnosis before/after figures), and an estimated frequency
response with its σ and coherence.  The ``plot_*`` functions draw on the ``Axes`` they are given
and return them; the writers make a figure with them and write it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from physmodel.errors import IPMCError

from .canvas import axes_grid, new_figure, save_figure, temperature_colors

__all__ = ["calibration_figure", "diagnosis_figures", "frf_estimate", "plot_calibration", "plot_residual_bode",
           "residual_bode", "residual_bode_pair"]


def plot_calibration(data, result, axes=None, *, model=None):
    """A calibration against its data on the given axes: the data as markers and the calibrated
    model as lines (magnitude and phase), and their standardised residuals beside them, one colour
    per temperature (the ``viridis`` map); returns ``axes``.

    Parameters
    ----------
    data : FrequencySweep
        The sweep the model was calibrated to (with its per-line σ, which scale the residuals).
    result : CalibrationResult or None
        What :func:`physmodel.calibrate` returned; used only to compute ``model`` (None is
        accepted when ``model`` is given).
    axes : 2 × 2 Axes or None
        ``((magnitude, magnitude residual), (phase, phase residual))``, nested or flat in that
        order; None: a new figure (its axes returned).
    model : FrequencySweep or None
        The calibrated model on the data's lines; default
        :func:`physmodel.estimation.calibration.model_sweep` of ``result`` and ``data``.

    Returns
    -------
    Axes array
        ``axes`` as given (the new 2 × 2 array when None).  The residual panels carry a grey ±2
        band; titles and the legend (entries ``data <T> °C``) are left to the caller.
    """
    from physmodel.estimation.residuals import residuals

    ret, grid = axes_grid(axes, 2, 2, "magnitude, magnitude residual, phase, phase residual",
                          sharex=True, figsize=(11, 6.5))
    (ax_m, ax_rm), (ax_p, ax_rp) = grid
    if model is None:
        from physmodel.estimation.calibration import model_sweep

        model = model_sweep(result, data)
    r = residuals(model.response, data)
    n = data.frequency_hz.size
    colors = temperature_colors(data.temperatures(), "viridis", 0.85)
    mag_d, ph_d, mag_m, ph_m = data.magnitude_db, data.phase_deg, model.magnitude_db, model.phase_deg
    for t in data.temperatures():
        m = data.temperature_c == t
        c = colors[float(t)]
        f = data.frequency_hz[m]
        ax_m.semilogx(f, mag_d[m], "o", ms=3, color=c, label=f"data {t:g} °C")
        ax_m.semilogx(f, mag_m[m], "-", color=c)
        # plot the model phase on the data's branch (same unwrap offset at the first line)
        off = 360.0 * np.round((ph_d[m][0] - ph_m[m][0]) / 360.0)
        ax_p.semilogx(f, ph_d[m], "o", ms=3, color=c)
        ax_p.semilogx(f, ph_m[m] + off, "-", color=c)
        ax_rm.semilogx(f, r[:n][m], ".-", ms=3, lw=0.6, color=c)
        ax_rp.semilogx(f, r[n:][m], ".-", ms=3, lw=0.6, color=c)
    for ax in (ax_rm, ax_rp):
        ax.axhspan(-2, 2, color="0.92", zorder=0)
        ax.axhline(0, color="k", lw=0.6)
    ax_m.set_ylabel(f"magnitude [dB {data.output_unit}/{data.input_unit}]")
    ax_p.set_ylabel("phase [deg]")
    ax_rm.set_ylabel("log-magnitude residual / σ")
    ax_rp.set_ylabel("phase residual / σ")
    for ax in (ax_p, ax_rp):
        ax.set_xlabel("frequency [Hz]")
    for ax in grid.ravel():
        ax.grid(True, which="both", alpha=0.3)
    return ret


def calibration_figure(data, model, res, path) -> Path:
    """Write :func:`plot_calibration`'s figure (its legend, and the cost against its expectation
    in the title).

    Parameters
    ----------
    data : FrequencySweep
        The calibration data.
    model : FrequencySweep
        The calibrated model on the data's lines.
    res : CalibrationResult
        The calibration.
    path : str or Path
        The figure file.
    """
    fig, axes = new_figure(2, 2, sharex=True, figsize=(11, 6.5))
    plot_calibration(data, res, axes, model=model)
    (ax_m, ax_rm), _ = axes
    ax_m.legend(fontsize=7, ncol=2)
    ax_m.set_title("data (markers) and calibrated model (lines)")
    ax_rm.set_title(f"standardised residuals (band ±2); cost {res.cost:.4g}, expected {res.expected_cost:.4g}")
    fig.tight_layout()
    return save_figure(fig, path)


def plot_residual_bode(data, model, axes=None):
    """Data (±2σ bands) against a model's response and the standardised residuals, on the given
    axes, one colour per temperature (``C0``, ``C1``, ...); returns ``axes``.

    Parameters
    ----------
    data : FrequencySweep
        The measured sweep (σ from its per-line values, or the noise floor
        :func:`physmodel.estimation.residuals.noise_std` assumes without them).
    model : array_like or FrequencySweep
        The model's complex response at the data's lines (in the data's order and units), or a
        sweep holding it on the same lines.
    axes : three Axes or None
        ``(magnitude, phase, residuals)``; None: a new figure (its axes returned).  The residual
        panel holds the log-magnitude (solid) and phase (dashed) residuals over a grey ±2 band.

    Returns
    -------
    Axes array
        ``axes`` as given (the new three when None); titles and the legend are left to the caller.

    Raises
    ------
    ValueError
        When ``model`` is not on the data's lines.
    """
    G = np.asarray(getattr(model, "response", model), dtype=complex)
    if G.shape != data.response.shape:
        raise ValueError(f"model: expected the response at the data's {data.response.size} lines "
                         f"(shape {data.response.shape}), got shape {G.shape}")
    if hasattr(model, "frequency_hz") and not (np.array_equal(model.frequency_hz, data.frequency_hz)
                                               and np.array_equal(model.temperature_c, data.temperature_c)):
        raise ValueError("model: a sweep on other lines (frequencies or temperatures) than the data's")
    ret, grid = axes_grid(axes, 3, 1, "magnitude, phase, residuals", figsize=(7, 9), sharex=True)
    _draw_residual_bode(data, G, grid[:, 0])
    return ret


def _model_curves(data, G, s_ln, s_ph):
    """Per temperature of ``data``: its lines' mask, the model's magnitude [dB] and phase [deg]
    (on the data's branch: the same unwrap offset at the first line) and the standardised
    log-magnitude and phase residuals — what :func:`plot_residual_bode` draws of the model."""
    for t in data.temperatures():
        m = data.temperature_c == t
        ph_d = np.degrees(np.unwrap(np.angle(data.response[m])))
        ph_m = np.degrees(np.unwrap(np.angle(G[m])))
        ph_m += 360 * np.round((ph_d[0] - ph_m[0]) / 360)
        lr = np.log(data.response[m] / G[m])
        yield t, m, 20 * np.log10(np.abs(G[m])), ph_m, lr.real / s_ln[m], lr.imag / s_ph[m]


def _draw_residual_bode(data, G, ax) -> list:
    """:func:`plot_residual_bode` on the three Axes ``ax``; returns the model's lines per
    temperature ``(magnitude, phase, magnitude residual, phase residual)``."""
    from physmodel.estimation.residuals import noise_std

    s_ln, s_ph, _ = noise_std(data)
    handles = []
    for i, (t, m, mag_m, ph_m, r_mag, r_ph) in enumerate(_model_curves(data, G, s_ln, s_ph)):
        f = data.frequency_hz[m]
        col = f"C{i % 10}"
        mag_d = 20 * np.log10(np.abs(data.response[m]))
        sd = s_ln[m] * 20 / np.log(10)
        ax[0].fill_between(f, mag_d - 2 * sd, mag_d + 2 * sd, color=col, alpha=0.2)
        ax[0].semilogx(f, mag_d, ".", color=col, ms=3)
        (l_mag,) = ax[0].semilogx(f, mag_m, "-", color=col, label=f"{t:g} °C")
        ph_d = np.degrees(np.unwrap(np.angle(data.response[m])))
        sp = np.degrees(s_ph[m])
        ax[1].fill_between(f, ph_d - 2 * sp, ph_d + 2 * sp, color=col, alpha=0.2)
        ax[1].semilogx(f, ph_d, ".", color=col, ms=3)
        (l_ph,) = ax[1].semilogx(f, ph_m, "-", color=col)
        (l_rm,) = ax[2].semilogx(f, r_mag, "-", color=col)
        (l_rp,) = ax[2].semilogx(f, r_ph, "--", color=col)
        handles.append((l_mag, l_ph, l_rm, l_rp))
    ax[2].axhspan(-2, 2, color="0.85", zorder=0)
    ax[0].set_ylabel(f"magnitude [dB {data.output_unit}/{data.input_unit}]")
    ax[1].set_ylabel("phase [deg]")
    ax[2].set_ylabel("std. residual (— mag, -- phase)")
    ax[2].set_xlabel("frequency [Hz]")
    return handles


#: Subplot margins of :func:`residual_bode`'s 7 × 9 inch figure [fraction of the figure].
RESIDUAL_BODE_MARGINS = {"left": 0.13, "right": 0.975, "bottom": 0.065, "top": 0.96, "hspace": 0.09}


def residual_bode(path, data, G, title: str) -> Path:
    """Write :func:`plot_residual_bode`'s figure with a legend and ``title``.

    Parameters
    ----------
    path : str or Path
        The figure file.
    data : FrequencySweep
        The measured sweep.
    G : array_like
        The model's complex response at the data's lines.
    title : str
        Title (followed by "— data ±2σ bands, model lines").
    """
    fig, ax = new_figure(3, 1, figsize=(7, 9), sharex=True)
    # fixed margins instead of tight_layout, whose measuring pass is a second full draw (a third of
    # the figure's cost): what it chose for these panels (their tick labels have at most 5
    # characters), with room for a sixth
    fig.subplots_adjust(**RESIDUAL_BODE_MARGINS)
    plot_residual_bode(data, G, ax)
    ax[0].legend(fontsize=7)
    ax[0].set_title(title + " — data ±2σ bands, model lines")
    return save_figure(fig, path, dpi=90)


def residual_bode_pair(paths, data, models, titles) -> list[Path]:
    """:func:`residual_bode` of the same data against two models (a diagnosis's before and after)
    on one canvas: drawn with the first model and written, then the model's and the residuals'
    lines set to the second, the limits recomputed from everything drawn (as a new figure's
    autoscaling does: lines, bands, the ±2 band) and written again — the same two images as two
    calls of :func:`residual_bode`, without building the axes and their ticks twice.

    Parameters
    ----------
    paths : two str or Path
        The figure files.
    data : FrequencySweep
        The measured sweep.
    models : two array_like
        The models' complex responses at the data's lines.
    titles : two str
        Their titles (each followed by "— data ±2σ bands, model lines").
    """
    from physmodel.estimation.residuals import noise_std

    (p0, p1), (G0, G1), (t0, t1) = paths, models, titles
    G0, G1 = (np.asarray(getattr(g, "response", g), dtype=complex) for g in (G0, G1))
    for g in (G0, G1):
        if g.shape != data.response.shape:
            raise ValueError(f"model: expected the response at the data's {data.response.size} lines "
                             f"(shape {data.response.shape}), got shape {g.shape}")
    fig, ax = new_figure(3, 1, figsize=(7, 9), sharex=True)
    fig.subplots_adjust(**RESIDUAL_BODE_MARGINS)
    handles = _draw_residual_bode(data, G0, ax)
    ax[0].legend(fontsize=7)
    ax[0].set_title(t0 + " — data ±2σ bands, model lines")
    out = [save_figure(fig, p0, dpi=90)]
    s_ln, s_ph, _ = noise_std(data)
    for lines, (_, _, mag_m, ph_m, r_mag, r_ph) in zip(handles, _model_curves(data, G1, s_ln, s_ph)):
        for line, y in zip(lines, (mag_m, ph_m, r_mag, r_ph)):
            line.set_ydata(y)
    for a in ax:
        a.relim()                               # older matplotlib leaves collections (the bands) out: added
        for c in a.collections:
            a.update_datalim(c.get_datalim(a.transData))
        a.autoscale_view()
    ax[0].set_title(t1 + " — data ±2σ bands, model lines")
    out.append(save_figure(fig, p1, dpi=90))
    return out


def diagnosis_figures(diagnosis, folder) -> list[Path]:
    """bode_before.png and bode_after.png of a :class:`~physmodel.estimation.discrepancy.Diagnosis`
    (:func:`residual_bode_pair`)."""
    folder = Path(folder)
    return residual_bode_pair((folder / "bode_before.png", folder / "bode_after.png"), diagnosis.data,
                              (diagnosis.predicted_before, diagnosis.predicted_after),
                              ("baseline (before)", "after: + " + (", ".join(diagnosis.final_effects) or "nothing")))


def frf_estimate(items, path, title: str = "") -> Path:
    """An estimated frequency response with its ±2σ bands: magnitude, phase and the coherence
    (H1/H2) or the magnitude σ (stepped sine), one colour per record.

    ``items``: ``[(estimate, temperature_c, kept), ...]`` with a one-channel
    :class:`~physmodel.estimation.frf.FRFEstimate`, its temperature [°C] and a boolean mask of the
    lines written to the sweep (dropped lines are drawn as grey crosses).
    """
    items = list(items)
    if not items:
        raise IPMCError("frf_estimate: nothing to plot")
    with_coh = all(e.coherence is not None for e, _, _ in items)
    fig, (ax_m, ax_p, ax_c) = new_figure(3, 1, sharex=True, figsize=(7, 8.5))
    for i, (e, T, kept) in enumerate(items):
        col = f"C{i % 10}"
        f, H = e.frequency_hz, e.response[0]
        kept = np.asarray(kept, dtype=bool)
        finite = np.isfinite(H) & (H != 0)
        ok, off = kept & finite, ~kept & finite
        mag = np.full(f.shape, np.nan)
        mag[finite] = 20 * np.log10(np.abs(H[finite]))
        ph = np.full(f.shape, np.nan)
        if ok.any():
            ph[ok] = np.degrees(np.unwrap(np.angle(H[ok])))
        ph[off] = np.degrees(np.angle(H[off]))
        sm, sp = e.magnitude_std_db[0], e.phase_std_deg[0]
        band_m = np.where(ok & np.isfinite(sm), 2 * sm, np.nan)
        band_p = np.where(ok & np.isfinite(sp), 2 * sp, np.nan)
        ax_m.fill_between(f, mag - band_m, mag + band_m, color=col, alpha=0.25, lw=0)
        ax_m.semilogx(f[ok], mag[ok], ".-", color=col, ms=3, lw=0.8, label=f"{T:g} °C")
        ax_p.fill_between(f, ph - band_p, ph + band_p, color=col, alpha=0.25, lw=0)
        ax_p.semilogx(f[ok], ph[ok], ".-", color=col, ms=3, lw=0.8)
        if off.any():
            ax_m.semilogx(f[off], mag[off], "x", color="0.6", ms=3)
            ax_p.semilogx(f[off], ph[off], "x", color="0.6", ms=3)
        if with_coh:
            ax_c.semilogx(f, e.coherence[0], ".-", color=col, ms=2, lw=0.6)
        else:
            ax_c.semilogx(f[ok], sm[ok], ".-", color=col, ms=3, lw=0.6)
    e0 = items[0][0]
    ax_m.set_ylabel(f"magnitude [dB {e0.output_units[0]}/{e0.input_unit}]")
    ax_p.set_ylabel("phase [deg]")
    if with_coh:
        ax_c.set_ylabel("coherence γ²")
        ax_c.set_ylim(-0.02, 1.02)
    else:
        ax_c.set_ylabel("σ of magnitude [dB]")
        ax_c.set_yscale("log")
    ax_c.set_xlabel("frequency [Hz]")
    for ax in (ax_m, ax_p, ax_c):
        ax.grid(True, which="both", alpha=0.3)
    ax_m.legend(fontsize=7, ncol=2)
    ax_m.set_title((title + "\n" if title else "") + "estimate with ±2σ bands (grey x: lines dropped)", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)
