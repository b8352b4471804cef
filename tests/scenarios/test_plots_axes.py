"""The remaining writers' ``plot_*`` forms draw on a user's Axes (issue 26 item 4).

``plot_calibration``, ``plot_residual_bode``, ``plot_pole_zero_locus``,
``plot_poles_zeros_vs_temperature`` and ``plot_pole_zero_maps``: each draws on Axes the test made
(a ``Figure`` on an Agg canvas, no pyplot), returns them as given, leaves pyplot's figures alone
and never saves, shows or closes a figure; the artists hold the data, read back from the lines
and compared with values computed here (a response with a known distortion, residuals from
their definition, models written here with roots in closed form) — not with the library's own
numbers.  Wrong numbers of Axes are a ValueError naming what is expected.
"""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from physmodel import ActuatorModel, IPMCError, MagnitudePhaseNoise, calibrate, get_parameter_set, synthesize_sweep
from physmodel.data.sweep import FrequencySweep
from scenarios import plots
from scenarios.plots import (
    plot_calibration,
    plot_pole_zero_locus,
    plot_pole_zero_maps,
    plot_poles_zeros_vs_temperature,
    plot_residual_bode,
)

BASE = get_parameter_set("seed002_table3")
F = np.array([0.5, 1.0, 2.0, 4.0, 8.0])
TEMPS = (20.0, 40.0)
#: data = model × this, per line: the residuals are its log-magnitude and angle over σ
DISTORTION = np.array([1.02, 0.97 * np.exp(0.05j), 1.1, np.exp(-0.1j), 0.9])
SDB = np.array([0.1, 0.2, 0.3, 0.2, 0.1])          # [dB]
SDEG = np.array([1.0, 2.0, 1.5, 1.0, 3.0])          # [deg]


def _figure(rows, cols):
    fig = Figure()
    FigureCanvasAgg(fig)
    return fig, fig.subplots(rows, cols, squeeze=False)


@pytest.fixture(autouse=True)
def _no_saving_showing_or_closing(monkeypatch):
    """A plot_* function that saved, showed or closed a figure fails here; pyplot's figures are
    counted before and after."""
    def refuse(*args, **kwargs):
        raise AssertionError("a plot_* function must not save, show or close a figure")

    monkeypatch.setattr(Figure, "savefig", refuse)
    monkeypatch.setattr(plt, "show", refuse)
    monkeypatch.setattr(plt, "close", refuse)
    before = plt.get_fignums()
    yield
    assert plt.get_fignums() == before


def _pair():
    """A model response G (the physics at TEMPS, mm/V) and data = G · DISTORTION with σ SDB/SDEG."""
    G = np.concatenate([ActuatorModel(BASE).response(F, [t])[0] * 1e3 for t in TEMPS])
    temps = np.repeat(TEMPS, F.size)
    f = np.tile(F, len(TEMPS))
    data = FrequencySweep(temps, f, G * np.tile(DISTORTION, len(TEMPS)), np.tile(SDB, len(TEMPS)),
                          np.tile(SDEG, len(TEMPS)), "voltage", "V", "tip_displacement", "mm")
    model = FrequencySweep(temps, f, G, None, None, "voltage", "V", "tip_displacement", "mm")
    return data, model, G


def _db(H):
    return 20 * np.log10(np.abs(H))


# residuals from their definition (ln|data/model| / σ_ln, angle(data/model) / σ_φ)
R_MAG = np.log(np.abs(DISTORTION)) / (SDB * math.log(10) / 20)
R_PH = np.angle(DISTORTION) / np.radians(SDEG)


# ----------------------------------------------------------------------------- plot_calibration
def test_plot_calibration_draws_data_model_and_residuals_on_the_given_grid():
    data, model, G = _pair()
    fig, axes = _figure(2, 2)
    assert plot_calibration(data, None, axes, model=model) is axes
    assert len(fig.axes) == 4
    (ax_m, ax_rm), (ax_p, ax_rp) = axes
    for i, t in enumerate(TEMPS):
        sl = slice(i * F.size, (i + 1) * F.size)
        d_line, m_line = ax_m.get_lines()[2 * i: 2 * i + 2]
        np.testing.assert_allclose(d_line.get_xdata(), F)
        np.testing.assert_allclose(d_line.get_ydata(), _db(data.response[sl]), rtol=1e-12)
        np.testing.assert_allclose(m_line.get_ydata(), _db(G[sl]), rtol=1e-12)
        assert d_line.get_label() == f"data {t:g} °C" and d_line.get_marker() == "o"
        # the model's phase is drawn on the data's branch: the difference is the distortion's angle
        dp, mp = ax_p.get_lines()[2 * i: 2 * i + 2]
        np.testing.assert_allclose(dp.get_ydata() - mp.get_ydata(), np.degrees(np.angle(DISTORTION)), atol=1e-9)
        np.testing.assert_allclose(ax_rm.get_lines()[i].get_ydata(), R_MAG, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(ax_rp.get_lines()[i].get_ydata(), R_PH, rtol=1e-9, atol=1e-12)
    assert ax_m.get_xscale() == "log" and "mm/V" in ax_m.get_ylabel() and ax_rp.get_xlabel() == "frequency [Hz]"
    assert ax_m.get_title() == "" and ax_m.get_legend() is None          # titles and legend: the caller's


def test_plot_calibration_computes_the_model_from_the_result_and_takes_a_flat_sequence():
    data = synthesize_sweep(ActuatorModel(BASE.replace(d=1.2 * BASE.d)), "M", F, [30.0],
                            noise=MagnitudePhaseNoise(0.2, 2.0), seed=1)
    res = calibrate(data, BASE, ["d"], starts=1, seed=0)
    fig, axes = _figure(2, 2)
    flat = list(axes.ravel())
    assert plot_calibration(data, res, flat) is flat
    want = _db(ActuatorModel(res.parameters).response(F, [30.0])[0] * 1e3)     # m/V -> mm/V
    np.testing.assert_allclose(flat[0].get_lines()[1].get_ydata(), want, rtol=1e-9)


def test_plot_calibration_without_axes_makes_a_figure_of_its_own():
    data, model, _ = _pair()
    axes = plot_calibration(data, None, model=model)
    assert axes.shape == (2, 2) and axes[0, 0].figure is axes[1, 1].figure
    assert len(axes[0, 0].get_lines()) == 2 * len(TEMPS)


# ----------------------------------------------------------------------------- plot_residual_bode
def test_plot_residual_bode_draws_bands_model_and_residuals():
    data, model, G = _pair()
    fig, axes = _figure(3, 1)
    col = axes[:, 0]
    assert plot_residual_bode(data, G, col) is col
    ax_m, ax_p, ax_r = col
    for i in range(len(TEMPS)):
        sl = slice(i * F.size, (i + 1) * F.size)
        d_line, m_line = ax_m.get_lines()[2 * i: 2 * i + 2]
        np.testing.assert_allclose(d_line.get_ydata(), _db(data.response[sl]), rtol=1e-12)
        np.testing.assert_allclose(m_line.get_ydata(), _db(G[sl]), rtol=1e-12)
        # the ±2σ band's outline: at each line its edges are 4σ apart
        v = ax_m.collections[i].get_paths()[0].vertices
        width = np.array([np.ptp(v[np.isclose(v[:, 0], f, rtol=1e-12), 1]) for f in F])
        np.testing.assert_allclose(width, 4 * SDB, rtol=1e-9)
        mag_r, ph_r = ax_r.get_lines()[2 * i: 2 * i + 2]
        np.testing.assert_allclose(mag_r.get_ydata(), R_MAG, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(ph_r.get_ydata(), R_PH, rtol=1e-9, atol=1e-12)
        assert mag_r.get_linestyle() == "-" and ph_r.get_linestyle() == "--"
    assert [ln.get_label() for ln in ax_m.get_lines()[1::2]] == [f"{t:g} °C" for t in TEMPS]


def test_plot_residual_bode_takes_a_model_sweep_on_the_same_lines_and_refuses_others():
    data, model, G = _pair()
    _, axes = _figure(3, 1)
    plot_residual_bode(data, model, axes[:, 0])
    np.testing.assert_allclose(axes[2, 0].get_lines()[0].get_ydata(), R_MAG, rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="10 lines"):
        plot_residual_bode(data, G[:4], axes[:, 0])
    shifted = FrequencySweep(model.temperature_c, model.frequency_hz * 1.01, G, None, None,
                             "voltage", "V", "tip_displacement", "mm")
    with pytest.raises(ValueError, match="other lines"):
        plot_residual_bode(data, shifted, axes[:, 0])
    with pytest.raises(ValueError, match=r"give 3 Axes \(magnitude, phase, residuals\), got 2"):
        plot_residual_bode(data, G, axes[:2, 0])


# ----------------------------------------------------------------------------- roots
class _Scheduled:
    """A scheduled model written here: poles −T ± 10j·(1 + T/100) and −50, a zero at −2T [rad/s]."""

    is_scheduled = True
    temperature_range_c = (10.0, 50.0)

    def poles(self, t, extrapolate=False):
        return np.array([-t + 10j * (1 + t / 100), -t - 10j * (1 + t / 100), -50.0 + 0j])

    def zeros(self, t, extrapolate=False):
        return np.array([-2.0 * t + 0j])


class _Fixed:
    """A per-temperature model: its own roots."""

    def __init__(self, t):
        self.t = t

    def poles(self):
        return _Scheduled().poles(self.t) + 1.0

    def zeros(self):
        return _Scheduled().zeros(self.t) + 1.0


def test_plot_pole_zero_locus_scatters_the_roots_at_each_temperature():
    fig, axes = _figure(1, 1)
    ax = axes[0, 0]
    temps = [15.0, 30.0, 45.0]
    assert plot_pole_zero_locus(_Scheduled(), temps, ax) is ax
    assert len(fig.axes) == 2                                          # and its colour bar
    zs, ps = ax.collections[0::2], ax.collections[1::2]
    for t, z, p in zip(temps, zs, ps):
        np.testing.assert_allclose(z.get_offsets(), [[-2 * t, 0.0]])
        np.testing.assert_allclose(p.get_offsets(), [[-t, 10 * (1 + t / 100)], [-t, -10 * (1 + t / 100)],
                                                     [-50.0, 0.0]])
    assert ax.get_xscale() == "symlog"
    # colours run cold to warm
    assert ps[0].get_facecolor()[0][0] < ps[-1].get_facecolor()[0][0]
    fig2, axes2 = _figure(1, 1)
    plot_pole_zero_locus(_Scheduled(), temps, axes2[0, 0], colorbar=False)
    assert len(fig2.axes) == 1


def test_plot_poles_zeros_vs_temperature_draws_real_and_imaginary_parts():
    fig, axes = _figure(2, 2)
    fits = {20.0: _Fixed(20.0), 40.0: _Fixed(40.0)}
    assert plot_poles_zeros_vs_temperature(_Scheduled(), axes, per_temperature_models=fits,
                                           n_temperatures=5) is axes
    grid = np.linspace(10.0, 50.0, 5)
    (p_re, z_re), (p_im, z_im) = axes
    sched, crosses = p_re.get_lines()
    np.testing.assert_allclose(sched.get_xdata(), np.repeat(grid, 3))
    np.testing.assert_allclose(sched.get_ydata(), np.ravel([[-t, -t, -50.0] for t in grid]))
    np.testing.assert_allclose(p_im.get_lines()[0].get_ydata(),
                               np.ravel([[10 * (1 + t / 100), -10 * (1 + t / 100), 0.0] for t in grid]))
    np.testing.assert_allclose(z_re.get_lines()[0].get_ydata(), -2 * grid)
    np.testing.assert_allclose(crosses.get_xdata(), [20.0] * 3 + [40.0] * 3)
    np.testing.assert_allclose(crosses.get_ydata(), [-19.0, -19.0, -49.0, -39.0, -39.0, -49.0])
    np.testing.assert_allclose(z_re.get_lines()[1].get_ydata(), [-39.0, -79.0])
    assert [a.get_title() for a in axes[0]] == ["poles", "zeros"]


def test_plot_poles_zeros_vs_temperature_refuses_an_unscheduled_model():
    class Plain(_Scheduled):
        is_scheduled = False

    _, axes = _figure(2, 2)
    with pytest.raises(IPMCError, match="scheduled"):
        plot_poles_zeros_vs_temperature(Plain(), axes)


def test_plot_pole_zero_maps_draws_one_map_per_model_and_counts_rhp_zeros():
    models = {"a": ([2.0, -1.0 + 1j, -1.0 - 1j], [-3.0, -0.5 + 4j, -0.5 - 4j]), "b": ([], [-1.0])}
    fig, axes = _figure(1, 2)
    assert plot_pole_zero_maps(models, axes) is axes
    a, b = axes[0]
    poles, zeros = a.get_lines()[:2]
    np.testing.assert_allclose(poles.get_xdata(), [-3.0, -0.5, -0.5])
    np.testing.assert_allclose(poles.get_ydata(), [0.0, 4.0, -4.0])
    np.testing.assert_allclose(zeros.get_xdata(), [2.0, -1.0, -1.0])
    np.testing.assert_allclose(zeros.get_ydata(), [0.0, 1.0, -1.0])
    assert a.get_title() == "a\n1 RHP zero(s)" and b.get_title() == "b\n0 RHP zero(s)"
    one = _figure(1, 1)[1][0, 0]
    assert plot_pole_zero_maps({"b": models["b"]}, one) is one       # a single Axes for a single model
    with pytest.raises(ValueError, match=r"give 2 Axes \(one per model: a, b\), got 1"):
        plot_pole_zero_maps(models, one)


def test_the_writers_are_still_there_and_write_through_the_plot_functions(tmp_path, monkeypatch):
    """The writers call the plot_* functions (one drawing code path): a writer whose plot_* is
    replaced draws what the replacement drew."""
    monkeypatch.undo()                                                  # the writers save
    seen = []
    real = plots.roots.plot_pole_zero_maps
    monkeypatch.setattr(plots.roots, "plot_pole_zero_maps", lambda m, ax: seen.append(m) or real(m, ax))
    path = plots.pole_zero_maps({"a": ([1.0], [-1.0])}, tmp_path / "m.png")
    assert seen and path.stat().st_size > 0


def test_without_axes_each_plot_function_makes_a_figure_of_its_own():
    data, _, G = _pair()
    col = plot_residual_bode(data, G)
    assert len(col) == 3 and len(col[2].get_lines()) == 2 * len(TEMPS)
    ax = plot_pole_zero_locus(_Scheduled(), [20.0, 30.0])
    assert len(ax.collections) == 4 and len(ax.figure.axes) == 2
    grid = plot_poles_zeros_vs_temperature(_Scheduled(), n_temperatures=3)
    assert grid.shape == (2, 2) and grid[1, 1].get_lines()[0].get_ydata().size == 3
    maps = plot_pole_zero_maps({"a": ([], [-1.0]), "b": ([1.0], [-2.0])})
    assert maps.shape == (1, 2) and maps[0, 1].get_title() == "b\n1 RHP zero(s)"
