"""Figures for reports: Bode plots of sweeps and time traces.  matplotlib with the Agg backend;
every figure is written atomically (temporary file, then rename)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path) -> Path:
    from physmodel.data.files import atomic_write

    path = Path(path)
    try:
        return atomic_write(path, lambda fh: fig.savefig(fh, format=path.suffix.lstrip(".") or "png", dpi=120), "wb")
    finally:
        _plt().close(fig)


def bode(sweeps, path, title: str = "", labels=None, styles=None) -> Path:
    """Bode plot of one or more :class:`~physmodel.data.sweep.FrequencySweep` (one line per temperature).

    ``sweeps``: a sweep or a list of sweeps drawn with the given ``styles`` (e.g. data as markers,
    model as lines).
    """
    from physmodel.data.sweep import FrequencySweep

    plt = _plt()
    if isinstance(sweeps, FrequencySweep):
        sweeps = [sweeps]
    labels = labels or [""] * len(sweeps)
    styles = styles or ["-"] * len(sweeps)
    fig, (ax_m, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
    temps = np.unique(np.concatenate([s.temperatures() for s in sweeps]))
    cmap = plt.get_cmap("coolwarm")
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
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
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
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4))
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
    plt = _plt()
    temps = np.asarray(temperatures_c, float)
    fig, ax = plt.subplots(figsize=(7, 5))
    cmap = plt.get_cmap("coolwarm")
    norm = plt.Normalize(temps.min(), temps.max() if temps.max() > temps.min() else temps.min() + 1)
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
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax, label="temperature [°C]")
    ax.set_title(title or "poles (x) and zeros (o) vs temperature")
    fig.tight_layout()
    return _save(fig, path)


def tracking(t, reference, achieved, path, title: str = "", unit: str = "mm",
             labels=("reference", "achieved"), window=None) -> Path:
    """Reference and achieved signals (top) and their error (bottom); ``window`` shades the
    interval over which the error bound is taken."""
    plt = _plt()
    fig, (a1, a2) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
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
