"""The one uniform-time check (physmodel.data.timerecord.uniform_interval) behind simulation,
inversion and frequency-response estimation.

Oracles: the offending sample is placed by the test (a known jitter or drift written into an
exact grid), and the block-wise check of a long record must name the same sample as a check of
the whole array at once.
"""

import numpy as np
import pytest

import inversion
from inversion import NonUniformSamplingError
from physmodel.data.timerecord import GRID_TOL, sample_rate, uniform_interval
from physmodel.data.timesim import check_uniform_time
from physmodel.errors import IPMCError

H = 1e-3


def _grid(n):
    return np.arange(n) * H


def test_every_entry_point_names_the_same_sample():
    t = _grid(50)
    t[17] += 0.01 * H                     # one late sample: steps 16->17 and 17->18 are off by 1 %
    msgs = []
    for check in (uniform_interval, check_uniform_time, inversion.sampling_interval,
                  lambda x: sample_rate(x, x.size)):
        with pytest.raises(IPMCError) as exc:
            check(t)
        msgs.append(str(exc.value))
    for m in msgs:
        assert "sample 17" in m and "t[17] - t[16]" in m, m
    # the inversion keeps its own error class (a subclass of IPMCError)
    with pytest.raises(NonUniformSamplingError):
        inversion.sampling_interval(t)


def test_exact_grids_pass_and_return_the_step():
    t = 5.0 + _grid(10_001)
    assert uniform_interval(t) == pytest.approx(H, rel=1e-12)
    assert inversion.sampling_interval(t) == uniform_interval(t)
    assert sample_rate(t, t.size) == pytest.approx(1 / H, rel=1e-12)
    # a time base accumulated by summation carries only rounding: accepted
    acc = np.cumsum(np.full(100_000, H)) - H
    assert uniform_interval(acc) == pytest.approx(H, rel=1e-9)


def test_tolerances_step_and_grid():
    t = _grid(1001)
    t[500] += 5e-7 * H                    # 5e-7 of a step: within the default 1e-6 per step
    uniform_interval(t)
    t[500] += 2e-6 * H
    with pytest.raises(IPMCError, match="sample 500"):
        uniform_interval(t)
    # measured records (sample_rate): 1e-4 of a step of jitter is fine, 3e-3 is not
    t = _grid(1001)
    t[300] += 1e-4 * H
    assert sample_rate(t, t.size) == pytest.approx(1 / H)
    t[300] += 3e-3 * H
    with pytest.raises(IPMCError, match="sample 300"):
        sample_rate(t, t.size)


def test_slow_drift_is_refused_by_the_grid_test():
    # every step within 1e-5 of the mean step, but the middle of the record lies 1.2 % of a
    # step off the grid through the end points (a clock that runs slow, then fast)
    n = 2001
    k = np.arange(n)
    t = (k + 0.012 * np.sin(np.pi * k / (n - 1))) * H
    steps = np.diff(t)
    assert np.max(np.abs(steps - H)) < 2e-5 * H
    worst = int(np.argmax(np.abs(t - k * H)))
    assert abs(t[worst] - worst * H) > GRID_TOL * H
    with pytest.raises(IPMCError, match=f"sample {worst} "):
        uniform_interval(t, rtol=1e-4)


def test_blocks_find_the_same_sample_as_the_whole_array():
    t = _grid(10_000)
    t[7321] -= 0.2 * H
    with pytest.raises(IPMCError) as whole:
        uniform_interval(t)
    with pytest.raises(IPMCError) as blocks:
        uniform_interval(t, block_samples=1000)
    assert str(whole.value) == str(blocks.value)
    # the step that crosses a block boundary is checked too
    t = _grid(4000)
    t[2000:] += 0.5 * H
    with pytest.raises(IPMCError, match=r"t\[2000\] - t\[1999\]"):
        uniform_interval(t, block_samples=1000)


@pytest.mark.parametrize("t, match", [
    (-1e-3, "positive"), (float("nan"), "positive"), ("fast", "number"),
    (np.r_[0.0, -1.0, -2.0], "increase"), (np.r_[0.0, np.nan, 2.0], "sample 1"),
    (np.r_[0.0], "at least 2"), (np.zeros((2, 2)), "1-D"),
])
def test_bad_time_bases_are_named(t, match):
    with pytest.raises(IPMCError, match=match):
        uniform_interval(t)
