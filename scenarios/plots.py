"""Every figure of the library: Bode plots of sweeps, surrogate fits and calibrated or diagnosed
models, pole/zero loci, time traces.  matplotlib ``Figure`` objects on an Agg canvas (no pyplot
state, safe in threads and workers); every figure is written atomically (temporary file, then
rename) through :func:`physmodel.data.files.atomic_write`.  The only module that imports matplotlib.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from physmodel.errors import IPMCError


def _subplots(*args, figsize=None, **kw):
    """A new ``Figure`` on an Agg canvas and its axes (like ``pyplot.subplots``, without pyplot state)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig, fig.subplots(*args, **kw)


def _cmap(name: str):
    import matplotlib

    return matplotlib.colormaps[name]


def _normalize(vmin, vmax):
    from matplotlib.colors import Normalize

    return Normalize(vmin, vmax)


def _scalar_mappable(**kw):
    from matplotlib.cm import ScalarMappable

    return ScalarMappable(**kw)


def _save(fig, path, dpi: int = 120) -> Path:
    from physmodel.data.files import atomic_write

    path = Path(path)
    return atomic_write(path, lambda fh: fig.savefig(fh, format=path.suffix.lstrip(".") or "png", dpi=dpi), "wb")


def bode(sweeps, path, title: str = "", labels=None, styles=None) -> Path:
    """Bode plot of one or more :class:`~physmodel.data.sweep.FrequencySweep` (one line per temperature).

    ``sweeps``: a sweep or a list of sweeps drawn with the given ``styles`` (e.g. data as markers,
    model as lines).
    """
    from physmodel.data.sweep import FrequencySweep

    if isinstance(sweeps, FrequencySweep):
        sweeps = [sweeps]
    labels = labels or [""] * len(sweeps)
    styles = styles or ["-"] * len(sweeps)
    fig, (ax_m, ax_p) = _subplots(2, 1, sharex=True, figsize=(7, 6))
    temps = np.unique(np.concatenate([s.temperatures() for s in sweeps]))
    cmap = _cmap("coolwarm")
    colors = {t: cmap(0.0 if temps.size == 1 else (t - temps.min()) / (temps.max() - temps.min())) for t in temps}
    for sw, lab, sty in zip(sweeps, labels, styles):
        mag, ph = sw.magnitude_db, sw.phase_deg
        for t in sw.temperatures():
            m = sw.temperature_c == t
            kw = dict(color=colors[t], label=f"{lab}{' ' if lab else ''}{t:g} °C")
            if sty in ("o", ".", "x"):
                ax_m.semilogx(sw.frequency_hz[m], mag[m], sty, ms=3, **kw)
                ax_p.semilogx(sw.frequency_hz[m], ph[m], sty, ms=3, **kw)
            else:
                ax_m.semilogx(sw.frequency_hz[m], mag[m], sty, **kw)
                ax_p.semilogx(sw.frequency_hz[m], ph[m], sty, **kw)
    sw0 = sweeps[0]
    ax_m.set_ylabel(f"magnitude [dB {sw0.output_unit}/{sw0.input_unit}]")
    ax_p.set_ylabel("phase [deg]")
    ax_p.set_xlabel("frequency [Hz]")
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.grid(True, which="both", alpha=0.3)
    ax_m.legend(fontsize=7, ncol=2)
    ax_m.set_title(title or f"{sw0.output_name} / {sw0.input_name}")
    fig.tight_layout()
    return _save(fig, path)


def traces(ts, path, title: str = "", output_scale: float = 1.0, output_label: str | None = None) -> Path:
    """Input and output of a :class:`~physmodel.data.timesim.TimeSeries`."""
    fig, (a1, a2) = _subplots(2, 1, sharex=True, figsize=(7, 5))
    a1.plot(ts.t, ts.input, lw=0.8)
    a1.set_ylabel(f"{ts.input_name} [{ts.input_unit}]")
    a2.plot(ts.t, ts.output * output_scale, lw=0.8, label="recorded")
    if ts.clean_output is not None and not np.array_equal(ts.clean_output, ts.output):
        a2.plot(ts.t, ts.clean_output * output_scale, lw=0.8, label="noise-free")
        a2.legend(fontsize=8)
    a2.set_ylabel(output_label or f"{ts.output_name} [{ts.output_unit}]")
    a2.set_xlabel("time [s]")
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
    a1.set_title(title)
    fig.tight_layout()
    return _save(fig, path)


def curves(x, ys: dict, path, xlabel: str, ylabel: str, title: str = "", logx: bool = True) -> Path:
    """Several curves y(x) on one axis (e.g. model orders)."""
    fig, ax = _subplots(figsize=(7, 4))
    for lab, y in ys.items():
        (ax.semilogx if logx else ax.plot)(x, y, label=lab)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    return _save(fig, path)


def pole_zero_locus(model, temperatures_c, path, title: str = "") -> Path:
    """Poles (x) and zeros (o) of a scheduled surrogate across temperature, coloured by °C [rad/s]."""
    temps = np.asarray(temperatures_c, float)
    fig, ax = _subplots(figsize=(7, 5))
    cmap = _cmap("coolwarm")
    norm = _normalize(temps.min(), temps.max() if temps.max() > temps.min() else temps.min() + 1)
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
    sm = _scalar_mappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax, label="temperature [°C]")
    ax.set_title(title or "poles (x) and zeros (o) vs temperature")
    fig.tight_layout()
    return _save(fig, path)


def tracking(t, reference, achieved, path, title: str = "", unit: str = "mm",
             labels=("reference", "achieved"), window=None) -> Path:
    """Reference and achieved signals (top) and their error (bottom); ``window`` shades the
    interval over which the error bound is taken."""
    fig, (a1, a2) = _subplots(2, 1, sharex=True, figsize=(7, 5))
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
    return _save(fig, path)


# ---------------------------------------------------------------------------- surrogate fits
def save_bode(model, data, temperature_c, path, title=None) -> None:
    """Measured vs model magnitude [dB] and phase [deg] at one temperature."""
    d = data if temperature_c is None else data.at_temperature(temperature_c)
    order = np.argsort(d.frequency_hz)
    f = d.frequency_hz[order]
    hd = d.response[order]
    fd = np.geomspace(f.min(), f.max(), 400)
    t_eval = temperature_c if model.is_scheduled else None
    hm = model.frequency_response(fd, t_eval)
    fig, (ax1, ax2) = _subplots(2, 1, sharex=True, figsize=(6.4, 5.2))
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
    _save(fig, path, dpi=110)


def save_poles_zeros_vs_temperature(model, path, per_temperature_models=None,
                                    n_temperatures: int = 121) -> None:
    """Real and imaginary parts of poles and zeros [rad/s] against temperature [°C]."""
    if not model.is_scheduled:
        raise IPMCError("pole/zero-vs-temperature plots need a scheduled model")
    lo, hi = model.temperature_range_c
    grid = np.linspace(lo, hi, n_temperatures)
    fig, axes = _subplots(2, 2, sharex=True, figsize=(8.0, 6.0))
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
    _save(fig, path, dpi=110)


# ---------------------------------------------------------------------------- calibration and diagnosis
def calibration_figure(data, model, res, path) -> Path:
    """Bode overlay (data markers, model lines) and standardised residuals, one colour per temperature."""
    from physmodel.estimation.residuals import residuals

    fig, axes = _subplots(2, 2, sharex=True, figsize=(11, 6.5))
    (ax_m, ax_rm), (ax_p, ax_rp) = axes
    r = residuals(model.response, data)
    n = data.frequency_hz.size
    temps = data.temperatures()
    cmap = _cmap("viridis")
    mag_d, ph_d, mag_m, ph_m = data.magnitude_db, data.phase_deg, model.magnitude_db, model.phase_deg
    for t in temps:
        m = data.temperature_c == t
        c = cmap(0.0 if temps.size == 1 else 0.85 * (t - temps.min()) / (temps.max() - temps.min()))
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
    for ax in axes.ravel():
        ax.grid(True, which="both", alpha=0.3)
    ax_m.legend(fontsize=7, ncol=2)
    ax_m.set_title("data (markers) and calibrated model (lines)")
    ax_rm.set_title(f"standardised residuals (band ±2); cost {res.cost:.4g}, expected {res.expected_cost:.4g}")
    fig.tight_layout()
    return _save(fig, path)


def residual_bode(path, data, G, title: str) -> Path:
    """Data (±2σ bands) vs model and the standardised residuals, one colour per temperature."""
    from physmodel.estimation.residuals import noise_std

    s_ln, s_ph, _ = noise_std(data)
    temps = data.temperatures()
    fig, ax = _subplots(3, 1, figsize=(7, 9), sharex=True)
    for i, t in enumerate(temps):
        m = data.temperature_c == t
        f = data.frequency_hz[m]
        col = f"C{i % 10}"
        mag_d = 20 * np.log10(np.abs(data.response[m]))
        sd = s_ln[m] * 20 / np.log(10)
        ax[0].fill_between(f, mag_d - 2 * sd, mag_d + 2 * sd, color=col, alpha=0.2)
        ax[0].semilogx(f, mag_d, ".", color=col, ms=3)
        ax[0].semilogx(f, 20 * np.log10(np.abs(G[m])), "-", color=col, label=f"{t:g} °C")
        ph_d = np.degrees(np.unwrap(np.angle(data.response[m])))
        ph_m = np.degrees(np.unwrap(np.angle(G[m])))
        ph_m += 360 * np.round((ph_d[0] - ph_m[0]) / 360)
        sp = np.degrees(s_ph[m])
        ax[1].fill_between(f, ph_d - 2 * sp, ph_d + 2 * sp, color=col, alpha=0.2)
        ax[1].semilogx(f, ph_d, ".", color=col, ms=3)
        ax[1].semilogx(f, ph_m, "-", color=col)
        lr = np.log(data.response[m] / G[m])
        ax[2].semilogx(f, lr.real / s_ln[m], "-", color=col)
        ax[2].semilogx(f, lr.imag / s_ph[m], "--", color=col)
    ax[2].axhspan(-2, 2, color="0.85", zorder=0)
    ax[0].set_ylabel(f"magnitude [dB {data.output_unit}/{data.input_unit}]")
    ax[1].set_ylabel("phase [deg]")
    ax[2].set_ylabel("std. residual (— mag, -- phase)")
    ax[2].set_xlabel("frequency [Hz]")
    ax[0].legend(fontsize=7)
    ax[0].set_title(title + " — data ±2σ bands, model lines")
    fig.tight_layout()
    return _save(fig, path, dpi=90)




def diagnosis_figures(diagnosis, folder) -> list[Path]:
    """bode_before.png and bode_after.png of a :class:`~physmodel.estimation.discrepancy.Diagnosis`."""
    folder = Path(folder)
    return [residual_bode(folder / "bode_before.png", diagnosis.data, diagnosis.predicted_before, "baseline (before)"),
            residual_bode(folder / "bode_after.png", diagnosis.data, diagnosis.predicted_after,
                          "after: + " + (", ".join(diagnosis.final_effects) or "nothing"))]


# ---------------------------------------------------------------------------- inversion
def inversion_traces(path: str, t, u, y, ucol: str,
          ref, refcol, title: str) -> Path:
    """Input, reconstruction and (with a reference) its error against time."""
    rows = 3 if ref is not None else 2
    fig, axes = _subplots(rows, 1, sharex=True, figsize=(8, 2.4 * rows))
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
    return _save(fig, path, dpi=110)


# ---------------------------------------------------------------------------- FRF estimates
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
    fig, (ax_m, ax_p, ax_c) = _subplots(3, 1, sharex=True, figsize=(7, 8.5))
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
    return _save(fig, path)
