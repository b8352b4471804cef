"""Plots where people work and "model vs my data".

- ``plot_bode``/``plot_time``/``plot_compare`` draw on the Axes they are given and return them,
  with the artists a reader expects (data read back from the lines, not from the library);
- the model band: contains the nominal curve, scales as sqrt of the covariance scale (the delta
  method's property), and agrees with a Monte Carlo written here (parameters drawn from the
  covariance or the intervals, the model evaluated per draw through its public constructor);
- ``compare``'s fit % and χ² against numbers computed here with numpy on a small synthetic case;
- ``ipmc compare`` exit codes: 0 fits, 3 misfit (2 never), 2 bad input with a message.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from physmodel import ActuatorModel, MagnitudePhaseNoise, get_parameter_set, synthesize_sweep
from physmodel.data.sweep import FrequencySweep
from physmodel.model_file import ModelFile
from scenarios.cli import main
from scenarios.comparison import compare
from scenarios.plots import plot_bode, plot_compare, plot_time
from scenarios.prediction import Z95, predict_sweep

BASE = get_parameter_set("seed002_table3")
F = np.geomspace(0.2, 30.0, 25)
TEMPS = [20.0, 40.0]


def _axes(n=2):
    fig = Figure()
    FigureCanvasAgg(fig)
    return fig.subplots(n, 1, squeeze=False)[:, 0]


def _data(seed=3, sigma_db=0.2, sigma_deg=2.0, params=BASE, f=F, temps=TEMPS):
    return synthesize_sweep(ActuatorModel(params), "M", f, temps, noise=MagnitudePhaseNoise(sigma_db, sigma_deg),
                            seed=seed)


# ----------------------------------------------------------------------------- drawing on Axes
def test_plot_bode_draws_a_sweep_with_error_bars_on_the_given_axes():
    data = _data()
    ax_m, ax_p = _axes()
    pair = (ax_m, ax_p)
    assert plot_bode(data, pair, style="o") is pair
    assert len(ax_m.containers) == len(ax_p.containers) == len(TEMPS)          # one errorbar set per T
    for t, cont in zip(TEMPS, ax_m.containers):
        line, _, (bars,) = cont
        m = data.temperature_c == t
        np.testing.assert_allclose(line.get_xdata(), data.frequency_hz[m])
        np.testing.assert_allclose(line.get_ydata(), 20 * np.log10(np.abs(data.response[m])), rtol=1e-12)
        seg = np.array([s[:, 1] for s in bars.get_segments()])                   # ±2σ bars
        np.testing.assert_allclose(seg[:, 1] - seg[:, 0], 4 * 0.2, rtol=1e-9)
        assert cont.get_label() == f"{t:g} °C"
    assert ax_m.get_xscale() == "log" and "mm/V" in ax_m.get_ylabel()


def test_plot_bode_of_a_sweep_as_lines_draws_bands_and_one_axes_means_magnitude_only():
    data = _data()
    (ax,) = _axes(1)
    assert plot_bode(data, ax, style="-") is ax
    assert len(ax.get_lines()) == len(TEMPS) and len(ax.collections) == len(TEMPS)   # a line and a band per T
    (ax2,) = _axes(1)
    plot_bode(data, ax2, style="-", band=False)
    assert len(ax2.collections) == 0


def test_plot_bode_of_a_physics_model_at_temperatures():
    ax_m, ax_p = _axes()
    model = ActuatorModel(BASE)
    plot_bode(model, (ax_m, ax_p), temperatures_c=[25.0, 45.0, 65.0], frequency_hz=F)
    lines = ax_m.get_lines()
    assert len(lines) == 3 and len(ax_m.collections) == 0                     # a model object has no band
    want = 20 * np.log10(np.abs(model.response(F, [45.0])[0]) * 1e3)         # m/V -> mm/V
    np.testing.assert_allclose(lines[1].get_ydata(), want, rtol=1e-10)


def test_plot_time_and_plot_compare_return_the_axes_they_were_given():
    from physmodel.data.timesim import TimeSeries

    t = np.linspace(0, 1, 50)
    ts = TimeSeries(t=t, input=np.sin(t), output=np.cos(t), input_name="voltage", input_unit="V",
                    output_name="tip", output_unit="mm")
    pair = tuple(_axes())
    assert plot_time(ts, pair) is pair
    assert len(pair[0].get_lines()) == 1 and len(pair[1].get_lines()) == 1
    np.testing.assert_allclose(pair[1].get_lines()[0].get_ydata(), np.cos(t))
    res = compare(ModelFile("actuator", BASE), _data())
    pair = tuple(_axes())
    assert plot_compare(res, pair) is pair
    labels = [c.get_label() for c in pair[0].containers]
    assert labels == [f"{f.temperature_c:g} °C: fit {f.fit_percent:.1f} %" for f in res.fits]
    assert len(pair[0].get_lines()) >= 2 * len(TEMPS)                          # data and model per T


# ----------------------------------------------------------------------------- the model band
def _surrogate(scale=1.0, orders=(2, 3)):
    from surrogate import RationalFit, RationalModel

    data = _data(temps=[30.0], f=np.geomspace(0.2, 30, 40))
    m = RationalFit(*orders).fit(data).model
    return RationalModel(m.structure, m.params, m.scaling, m.temperature_range_c, covariance=scale * m.covariance,
                         labels=m.labels), data


def test_the_band_contains_the_nominal_curve_and_widens_as_sqrt_of_the_covariance_scale():
    (m1, data), (m4, _) = _surrogate(1.0), _surrogate(4.0)
    s1 = predict_sweep(m1, F, [30.0], like=data)
    s4 = predict_sweep(m4, F, [30.0], like=data)
    assert np.all(s1.magnitude_std_db > 0) and np.all(s1.phase_std_deg > 0)
    np.testing.assert_allclose(s4.magnitude_std_db, 2 * s1.magnitude_std_db, rtol=1e-9)
    np.testing.assert_allclose(s4.phase_std_deg, 2 * s1.phase_std_deg, rtol=1e-9)
    ax_m, ax_p = _axes()
    plot_bode(m1, (ax_m, ax_p), frequency_hz=F, temperatures_c=[30.0], like=data)
    (band,), (line,) = ax_m.collections, ax_m.get_lines()
    v = band.get_paths()[0].vertices                   # the band's outline: lower and upper edge at each f
    at = [v[np.isclose(v[:, 0], f, rtol=1e-12), 1] for f in F]
    lo, hi = np.array([a.min() for a in at]), np.array([a.max() for a in at])
    y = line.get_ydata()
    assert np.all(lo < y) and np.all(y < hi)
    np.testing.assert_allclose(hi - lo, 4 * s1.magnitude_std_db, rtol=1e-9)          # ±2σ


def test_the_surrogate_band_matches_a_monte_carlo_of_its_parameters():
    """Delta method vs parameters drawn from the covariance (a tenth of it: the linear regime the
    band claims), the surrogate rebuilt per draw with its public constructor."""
    from surrogate import RationalModel

    m, data = _surrogate(0.1)
    s = predict_sweep(m, F, [30.0], like=data)
    rng = np.random.default_rng(0)
    draws = rng.multivariate_normal(m.params, m.covariance, size=2000)
    H = np.array([RationalModel(m.structure, th, m.scaling, m.temperature_range_c).response(F)[0] for th in draws])
    H0 = m.response(F)[0]
    sd_db = np.std(20 * np.log10(np.abs(H / H0)), axis=0)
    sd_deg = np.std(np.degrees(np.angle(H / H0)), axis=0)
    # 2000 draws: the sample std is within ±3·(1/sqrt(2·2000)) ≈ ±5 % of the true one
    np.testing.assert_allclose(s.magnitude_std_db, sd_db, rtol=0.08)
    np.testing.assert_allclose(s.phase_std_deg, sd_deg, rtol=0.08)


@pytest.mark.parametrize("rho", [None, 0.9, -0.9])
def test_a_model_file_band_matches_a_monte_carlo_of_its_intervals(rho):
    """Two parameters with 95 % intervals (independent, or correlated as given), drawn from them
    (d log-normal, E normal) and evaluated as parameter sets of the plain ActuatorModel (not the
    predictor the band uses)."""
    d, E = BASE.d, BASE.E
    est = ({"name": "d", "value": d, "ci95": [d / 1.05, d * 1.05], "status": "determined"},
           {"name": "E", "value": E, "ci95": [E - 0.02 * E, E + 0.02 * E], "status": "determined"},
           {"name": "xi", "value": BASE.xi, "ci95": [None, None], "status": "held at base (undetermined)"})
    mf = ModelFile("actuator", BASE, estimates=est)
    R = np.eye(2) if rho is None else np.array([[1.0, rho], [rho, 1.0]])
    corr = None if rho is None else (["xi", "d", "E"], np.array([[1, np.nan, np.nan], [np.nan, 1, rho],
                                                                  [np.nan, rho, 1]]))
    s = predict_sweep(mf, F, [30.0], correlation=corr)
    assert "(d, E)" in s.metadata["notes"] and "xi" in s.metadata["notes"]
    z = np.random.default_rng(1).multivariate_normal([0.0, 0.0], R, size=2000)
    dd = d * np.exp(z[:, 0] * math.log(1.05) / Z95)
    EE = E + z[:, 1] * 0.02 * E / Z95
    sets = [BASE.replace(d=a, E=b) for a, b in zip(dd, EE)]
    H = ActuatorModel(sets).frequency_response(F, [30.0], quantities=("M",))["M"][:, 0, :]
    H0 = ActuatorModel(BASE).response(F, [30.0])[0]
    np.testing.assert_allclose(s.magnitude_std_db, np.std(20 * np.log10(np.abs(H / H0)), axis=0), rtol=0.1)
    np.testing.assert_allclose(s.phase_std_deg, np.std(np.degrees(np.angle(H / H0)), axis=0), rtol=0.1)


# ----------------------------------------------------------------------------- compare
def test_compare_fit_percent_and_chi2_against_numbers_computed_here():
    f = np.array([0.5, 1.0, 2.0, 4.0, 8.0])
    model = ActuatorModel(BASE)
    G = model.response(f, [25.0])[0] * 1e3                               # mm/V
    distortion = np.array([1.02, 0.97 * np.exp(0.05j), 1.1, np.exp(-0.1j), 0.9])
    y = G * distortion
    sdb, sdeg = np.array([0.1, 0.2, 0.3, 0.2, 0.1]), np.array([1.0, 2.0, 1.5, 1.0, 3.0])
    data = FrequencySweep(np.full(5, 25.0), f, y, sdb, sdeg, "voltage", "V", "tip_displacement", "mm")
    (fit,) = compare(model, data).fits
    want = 100 * (1 - np.sqrt(np.sum(np.abs(y - G) ** 2)) / np.sqrt(np.sum(np.abs(y - y.mean()) ** 2)))
    chi2 = np.sum((np.log(np.abs(distortion)) / (sdb * np.log(10) / 20)) ** 2) + \
        np.sum((np.angle(distortion) / np.radians(sdeg)) ** 2)
    assert fit.fit_percent == pytest.approx(want, rel=1e-9)
    assert fit.chi2 == pytest.approx(chi2, rel=1e-9) and fit.dof == 10
    from scipy.stats import chi2 as chi2_dist

    assert fit.p_value == pytest.approx(chi2_dist.sf(chi2, 10), rel=1e-9)
    assert fit.rms_db == pytest.approx(np.sqrt(np.mean((20 * np.log10(np.abs(distortion))) ** 2)), rel=1e-9)


def test_compare_a_perfect_model_is_100_percent():
    data = synthesize_sweep(ActuatorModel(BASE), "M", F, TEMPS)             # exact, no σ
    res = compare(ModelFile("actuator", BASE), data)
    assert all(f.fit_percent == pytest.approx(100.0, abs=1e-9) and f.chi2 is None for f in res.fits)
    assert res.adequate and any("no per-line σ" in n for n in res.notes)


# ----------------------------------------------------------------------------- ipmc compare
def _files(tmp_path, gain=1.0):
    data = _data()
    data = FrequencySweep(data.temperature_c, data.frequency_hz, data.response * gain, data.magnitude_std_db,
                          data.phase_std_deg, data.input_name, data.input_unit, data.output_name, data.output_unit)
    path = tmp_path / "data.csv"
    data.to_csv(path)
    model = tmp_path / "model.json"
    ModelFile("actuator", BASE).save(model)
    return model, path


def test_cli_compare_fits_and_writes_its_folder(tmp_path, capsys):
    model, data = _files(tmp_path)
    assert main(["compare", str(model), str(data), "-o", str(tmp_path / "out")]) == 0
    out = capsys.readouterr()
    assert "fit %" in out.out and out.err == ""
    rec = json.loads((tmp_path / "out" / "compare.json").read_text())
    assert rec["adequate"] and [t["temperature_c"] for t in rec["temperatures"]] == TEMPS
    assert (tmp_path / "out" / "compare.png").stat().st_size > 0


def test_cli_compare_misfit_is_exit_3_with_the_verdict_on_stderr(tmp_path, capsys):
    model, data = _files(tmp_path, gain=1.3)                              # +2.3 dB against σ = 0.2 dB
    assert main(["compare", str(model), str(data), "--quiet"]) == 3
    err = capsys.readouterr().err
    assert "DOES NOT FIT" in err and "20, 40 °C" in err
    assert main(["compare", str(model), str(data), "--quiet", "--accept-misfit"]) == 0
    assert "DOES NOT FIT" in capsys.readouterr().err


@pytest.mark.parametrize("orders, code", [((3, 4), 0), ((2, 3), 3)])
def test_cli_compare_a_surrogate_file(tmp_path, capsys, orders, code):
    """A 3/4 surrogate of the strip fits its 0.2 dB / 2° data (χ² 88 on 80); a 2/3 one cannot follow
    the mode and the diffusion corner together (0.6 dB RMS: χ² 538 on 80)."""
    m, data = _surrogate(orders=orders)
    m.to_json(tmp_path / "fit.json")
    data.to_csv(tmp_path / "d.csv")
    assert main(["compare", str(tmp_path / "fit.json"), str(tmp_path / "d.csv"), "-o", str(tmp_path / "o")]) == code
    err = capsys.readouterr().err
    assert ("DOES NOT FIT" in err) == (code == 3) and "Traceback" not in err
    assert json.loads((tmp_path / "o" / "compare.json").read_text())["adequate"] == (code == 0)


@pytest.mark.parametrize("case, needle", [
    ("missing data", "no such file"),
    ("data type", "unknown sweep type"),
    ("bad json", "not valid JSON"),
    ("wrong units", "tip_displacement"),
    ("out is a file", "not a folder"),
])
def test_cli_compare_bad_input_is_exit_2_with_a_message(tmp_path, capsys, case, needle):
    model, data = _files(tmp_path)
    args = [str(model), str(data)]
    if case == "missing data":
        args[1] = str(tmp_path / "nope.csv")
    elif case == "data type":
        (tmp_path / "d.txt").write_text("x")
        args[1] = str(tmp_path / "d.txt")
    elif case == "bad json":
        (tmp_path / "m.json").write_text("{oops")
        args[0] = str(tmp_path / "m.json")
    elif case == "wrong units":
        sensor = FrequencySweep(np.full(3, 30.0), [1.0, 2.0, 3.0], [1.0, 1.0, 1.0], None, None,
                                "tip_displacement", "mm", "current", "uA")
        sensor.to_csv(tmp_path / "s.csv")
        args[1] = str(tmp_path / "s.csv")
    elif case == "out is a file":
        (tmp_path / "f").write_text("x")
        args += ["-o", str(tmp_path / "f")]
    assert main(["compare", *args]) == 2
    err = capsys.readouterr().err
    assert needle in err and "Traceback" not in err


def test_a_model_file_band_at_an_effect_bound_takes_a_one_sided_step():
    """An effect parameter estimated at its bound (a delay of ~0 s, interval ±0.1 ms reaching below
    0) gave a band draw outside the values the effect accepts (exit 2 in ``ipmc compare``).  The
    step is kept inside; for e^{-sτ} the band is analytic: phase σ = ω σ_τ, magnitude σ = 0."""
    sd = 1e-4 / Z95
    est = ({"name": "time_delay.delay", "value": 1e-25, "ci95": [-1e-4, 1e-4], "status": "determined"},)
    mf = ModelFile("actuator", BASE, {"time_delay": {"delay": 1e-25}}, estimates=est)
    s = predict_sweep(mf, F, [30.0])
    np.testing.assert_allclose(s.phase_std_deg, np.degrees(2 * np.pi * F * sd), rtol=1e-6)
    np.testing.assert_allclose(s.magnitude_std_db, 0.0, atol=1e-9)
