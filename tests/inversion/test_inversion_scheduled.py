"""Inversion with a time-varying temperature (scheduled model).

Truth for the drifting bath: a time-warped sensor, x' = kappa(T(t)) (A x + B d),
i = g(T(t)) (C x + D d), whose frozen transfer function at every T is the toy scheduled model
g(T) G_35(s/kappa(T)) (inversion.examples.toy_scheduled_sensor); integrated by
scipy.integrate.solve_ivp (DOP853, rtol 1e-10) independently of the package.
"""

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.signal as ss
from scipy.integrate import solve_ivp

from inversion import (
    InversionError,
    NonFiniteSignalError,
    ScheduledStreamingInverter,
    invert,
    invert_scheduled,
    invert_scheduled_to,
    temperature_grid,
)
from inversion.examples import SEED000_DEN_35C, SEED000_NUM_35C, toy_scheduled_sensor

DT = 1e-3


def test_temperature_grid():
    np.testing.assert_allclose(temperature_grid(30.0, 33.0, 1.0), [30, 31, 32, 33])
    g = temperature_grid(30.0, 33.5, 1.0)
    assert g[0] == 30.0 and g[-1] == 33.5 and np.all(np.diff(g) <= 1.0)
    assert temperature_grid(35.0, 35.0).tolist() == [35.0]
    with pytest.raises(InversionError, match="positive"):
        temperature_grid(30, 40, 0.0)


def test_constant_temperature_equals_fixed_inverse():
    u = np.sin(2 * np.pi * 20 * DT * np.arange(2000))
    fixed = invert(toy_scheduled_sensor(37.0), DT, u, preview="4/r0").output
    r = invert_scheduled(toy_scheduled_sensor, DT, u, 37.0, preview="4/r0")
    np.testing.assert_array_equal(r.grid_c, [37.0])
    np.testing.assert_allclose(r.output, fixed, rtol=0, atol=1e-13)
    # between two nodes it is the linear interpolation of the two node inverses
    r2 = invert_scheduled(toy_scheduled_sensor, DT, u, 37.25, grid=[37.0, 38.0], preview=0.1)
    a = invert(toy_scheduled_sensor(37.0), DT, u, preview=0.1).output
    b = invert(toy_scheduled_sensor(38.0), DT, u, preview=0.1).output
    np.testing.assert_allclose(r2.output, 0.75 * a + 0.25 * b, rtol=0, atol=1e-13)


def _warped_sensor_current(t, d, T):
    A, B, C, D = ss.tf2ss(SEED000_NUM_35C, SEED000_DEN_35C)
    A, (sc, _) = sla.matrix_balance(A, permute=False, separate=True)
    B, C, D = B.ravel() / sc, C.ravel() * sc, float(D[0, 0])
    kap = lambda TT: 1 - 0.01 * (TT - 35)
    gain = lambda TT: 1 - 0.004 * (TT - 35)
    sol = solve_ivp(lambda tt, x: kap(T(tt)) * (A @ x + B * d(tt)), (t[0], t[-1]), np.zeros(4),
                    t_eval=t, method="DOP853", rtol=1e-10, atol=1e-12, max_step=2e-4)
    assert sol.success
    return gain(T(t)) * (C @ sol.y + D * d(t))


@pytest.fixture(scope="module")
def drift():
    dur = 2.5
    t = np.arange(0.0, dur, DT)
    T = lambda tt: 30.0 + 10.0 * tt / dur                  # bath drifts 30 -> 40 degC
    d = lambda tt: np.where(tt < 0.3, np.sin(np.pi * tt / 0.6) ** 2, 1.0) * np.sin(2 * np.pi * 20 * tt)
    i = _warped_sensor_current(t, d, T)
    return t, T(t), d(t), i


def test_drifting_bath_scheduled_inverse_beats_fixed_temperature(drift):
    t, T, d, i = drift
    m = (t > 0.5) & (t < t[-1] - 0.3)
    sched = invert_scheduled(toy_scheduled_sensor, t, i, T, preview="inf")
    fixed = invert(toy_scheduled_sensor(30.0), t, i, preview="inf")   # calibrated at start
    e_s = np.max(np.abs(sched.output[m] - d[m]))
    e_f = np.max(np.abs(fixed.output[m] - d[m]))
    assert e_s < 3e-3            # mm for a 1 mm stimulus (frozen-time + grid + discretisation)
    assert e_f / e_s > 20.0      # measured ~90x
    # with the automatic preview both include the same truncation error: still far better
    sched_a = invert_scheduled(toy_scheduled_sensor, t, i, T, preview="4/r0")
    fixed_a = invert(toy_scheduled_sensor(30.0), t, i, preview=sched_a.preview_s)
    assert sched_a.preview_s == pytest.approx(max(4 / r for r in sched_a.r0), abs=DT / 2)
    assert np.max(np.abs(fixed_a.output[m] - d[m])) > 2 * np.max(np.abs(sched_a.output[m] - d[m]))


def test_scheduled_streaming_and_bounded_memory_match_batch(drift, tmp_path):
    t, T, d, i = drift
    ref = invert_scheduled(toy_scheduled_sensor, DT, i, T, preview=0.1, grid_step=2.0)
    inv = ScheduledStreamingInverter(toy_scheduled_sensor, DT, (T.min(), T.max()), 0.1, grid_step=2.0)
    outs = [inv.push(i[k:k + 333], T[k:k + 333]) for k in range(0, i.size, 333)]
    outs.append(inv.flush())
    y = np.concatenate(outs)
    np.testing.assert_allclose(y, ref.output, rtol=0, atol=1e-12 * np.max(np.abs(ref.output)))
    n = i.size
    ui = np.lib.format.open_memmap(tmp_path / "i.npy", mode="w+", dtype=float, shape=(n,))
    ti = np.lib.format.open_memmap(tmp_path / "T.npy", mode="w+", dtype=float, shape=(n,))
    yo = np.lib.format.open_memmap(tmp_path / "y.npy", mode="w+", dtype=float, shape=(n,))
    ui[:], ti[:] = i, T
    g = invert_scheduled_to(toy_scheduled_sensor, DT, ui, ti, yo, preview=0.1, grid_step=2.0,
                            chunk_size=400)
    np.testing.assert_array_equal(g, ref.grid_c)
    np.testing.assert_allclose(np.asarray(yo), ref.output, rtol=0, atol=1e-12 * np.max(np.abs(ref.output)))


def test_scheduled_input_errors():
    u = np.zeros(100)
    with pytest.raises(NonFiniteSignalError, match="temperature"):
        invert_scheduled(toy_scheduled_sensor, DT, u, np.r_[np.full(99, 30.0), np.nan], preview="inf")
    with pytest.raises(InversionError, match="one value per sample"):
        invert_scheduled(toy_scheduled_sensor, DT, u, np.full(99, 30.0), preview="inf")
    with pytest.raises(InversionError, match="covers only"):
        invert_scheduled(toy_scheduled_sensor, DT, u, np.linspace(30, 40, 100), grid=[30, 35], preview="inf")
    inv = ScheduledStreamingInverter(toy_scheduled_sensor, DT, (30.0, 32.0), 0.05)
    with pytest.raises(InversionError, match="outside"):
        inv.push([0.0, 0.0], [31.0, 33.0])
