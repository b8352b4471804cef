"""Figures of fits against their data: the calibration overlay with standardised residuals, the
diagnosis before/after bands, and an estimated frequency response with its σ and coherence."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from physmodel.errors import IPMCError

from .canvas import colormap, new_figure, save_figure

__all__ = ["calibration_figure", "diagnosis_figures", "frf_estimate", "residual_bode"]


def calibration_figure(data, model, res, path) -> Path:
    """Bode overlay (data markers, model lines) and standardised residuals, one colour per temperature."""
    from physmodel.estimation.residuals import residuals

    fig, axes = new_figure(2, 2, sharex=True, figsize=(11, 6.5))
    (ax_m, ax_rm), (ax_p, ax_rp) = axes
    r = residuals(model.response, data)
    n = data.frequency_hz.size
    temps = data.temperatures()
    cmap = colormap("viridis")
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
    return save_figure(fig, path)


def residual_bode(path, data, G, title: str) -> Path:
    """Data (±2σ bands) vs model and the standardised residuals, one colour per temperature."""
    from physmodel.estimation.residuals import noise_std

    s_ln, s_ph, _ = noise_std(data)
    temps = data.temperatures()
    fig, ax = new_figure(3, 1, figsize=(7, 9), sharex=True)
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
    return save_figure(fig, path, dpi=90)

def diagnosis_figures(diagnosis, folder) -> list[Path]:
    """bode_before.png and bode_after.png of a :class:`~physmodel.estimation.discrepancy.Diagnosis`."""
    folder = Path(folder)
    return [residual_bode(folder / "bode_before.png", diagnosis.data, diagnosis.predicted_before, "baseline (before)"),
            residual_bode(folder / "bode_after.png", diagnosis.data, diagnosis.predicted_after,
                          "after: + " + (", ".join(diagnosis.final_effects) or "nothing"))]


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
