"""Report figures (matplotlib Agg canvas, no pyplot state; written atomically as PNG)."""

from __future__ import annotations

import io

import numpy as np

from ._data import FrequencyData
from ._io import atomic_write_bytes
from .models import RationalModel

__all__ = ["save_bode", "save_poles_zeros_vs_temperature"]


def _figure(w_in, h_in):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(w_in, h_in))
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    atomic_write_bytes(path, buf.getvalue())


def save_bode(model: RationalModel, data: FrequencyData, temperature_c, path, title=None) -> None:
    """Measured vs model magnitude [dB] and phase [deg] at one temperature."""
    d = data if temperature_c is None else data.at_temperature(temperature_c)
    order = np.argsort(d.frequency_hz)
    f = d.frequency_hz[order]
    hd = d.response[order]
    fd = np.geomspace(f.min(), f.max(), 400)
    t_eval = temperature_c if model.is_scheduled else None
    hm = model.frequency_response(fd, t_eval)
    fig = _figure(6.4, 5.2)
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
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
    _save(fig, path)


def save_poles_zeros_vs_temperature(model: RationalModel, path, per_temperature_models=None,
                                    n_temperatures: int = 121) -> None:
    """Real and imaginary parts of poles and zeros [rad/s] against temperature [°C]."""
    if not model.is_scheduled:
        raise ValueError("pole/zero-vs-temperature plots need a scheduled model")
    lo, hi = model.temperature_range_c
    grid = np.linspace(lo, hi, n_temperatures)
    fig = _figure(8.0, 6.0)
    axes = fig.subplots(2, 2, sharex=True)
    for col, (name, getter) in enumerate((("poles", model.poles), ("zeros", model.zeros))):
        tt, vals = [], []
        for t in grid:
            r = getter(t)
            tt += [t] * r.size
            vals += list(r)
        vals = np.asarray(vals, complex)
        axes[0, col].plot(tt, vals.real, ".", ms=2, label="scheduled model")
        axes[1, col].plot(tt, vals.imag, ".", ms=2)
        if per_temperature_models:
            pt, pv = [], []
            for t, m in per_temperature_models.items():
                r = m.poles() if name == "poles" else m.zeros()
                pt += [t] * r.size
                pv += list(r)
            pv = np.asarray(pv, complex)
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
    _save(fig, path)
