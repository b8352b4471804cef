"""Limits refuse or flag what a strip cannot take; references fade in and out.

Oracles: first violating samples located with plain numpy on the same arrays; the fade window
against its closed form (value, slope and curvature vanish at the joints); the end spike of an
unfaded reference compared with the faded one through the same inverse.
"""

import numpy as np
import pytest

from inversion import decode_sensor, feedforward
from inversion import references as R
from inversion.examples import toy_actuator
from inversion.limits import LimitError, Limits, LimitWarning, check_limits
from physmodel.errors import IPMCError

DT = 1e-3


def test_check_limits_names_the_first_violating_sample():
    t = np.arange(0, 2, DT)
    y = 3.0 * np.sin(2 * np.pi * t)
    with pytest.raises(LimitError) as exc:
        check_limits(y, DT, Limits(max_voltage=2.5), what="feedforward voltage", unit="V")
    first = int(np.flatnonzero(np.abs(y) > 2.5)[0])
    msg = str(exc.value)
    assert f"sample {first}" in msg and f"t = {first * DT:.6g} s" in msg and "2.5" in msg
    assert isinstance(exc.value, IPMCError)
    # rates: the first difference that exceeds the bound, reported at its later sample
    rate = np.abs(np.diff(y)) / DT
    with pytest.warns(LimitWarning, match=f"sample {int(np.flatnonzero(rate > 15.0)[0]) + 1}"):
        rep = check_limits(y, DT, Limits(max_rate=15.0, action="warn"), unit="V")
    assert not rep.ok and rep.violations[0].kind == "max_rate"
    assert rep.violations[0].count == int(np.sum(rate > 15.0))
    assert rep.peak == pytest.approx(3.0, rel=1e-6) and rep.peak_rate == pytest.approx(rate.max())
    ok = check_limits(y, DT, Limits(max_voltage=3.5, max_rate=100.0))
    assert ok.ok and ok.message == ""


def test_output_range_and_earliest_violation_first():
    y = np.r_[0.0, 0.5, 1.0, 2.5, -3.0, 0.0]
    with pytest.warns(LimitWarning):
        rep = check_limits(y, 0.1, Limits(max_voltage=2.8, output_range=(-2.0, 2.0), action="warn"))
    kinds = [(v.kind, v.index) for v in rep.violations]
    assert kinds == [("output_range", 3), ("max_voltage", 4)]
    assert rep.violations[0].limit == 2.0 and rep.violations[1].value == -3.0


@pytest.mark.parametrize("kw, match", [
    (dict(max_voltage=-1.0), "max_voltage"), (dict(max_rate=float("nan")), "max_rate"),
    (dict(output_range=(2.0, 1.0)), "lo < hi"), (dict(action="ignore"), "action"),
    (dict(output_range="wide"), "pair")])
def test_bad_limits_are_refused(kw, match):
    with pytest.raises(IPMCError, match=match):
        Limits(**kw)


def test_feedforward_and_decode_apply_limits():
    G = toy_actuator()
    ref = R.sine(1.0, 1.0, 6.0, 1 / DT)
    ff = feedforward(G, ref.t, ref.y)
    peak = ff.limit_report.peak
    assert peak == pytest.approx(np.max(np.abs(ff.output)))
    with pytest.raises(LimitError, match="feedforward voltage"):
        feedforward(G, ref.t, ref.y, limits=Limits(max_voltage=0.5 * peak))
    with pytest.warns(LimitWarning):
        r = feedforward(G, ref.t, ref.y, limits=Limits(max_voltage=0.5 * peak, action="warn"))
    assert not r.limit_report.ok
    with pytest.raises(LimitError, match="decoded signal .* outside the allowed range"):
        decode_sensor(G, ref.t, ref.y, limits=Limits(output_range=(-0.1, 0.1)))


# ------------------------------------------------------------------------------ references
def test_sine_reference_fades_smoothly_to_rest():
    ref = R.sine(0.3, 1.0, 8.0, 1 / DT, lead_s=1.0, tail_s=1.5, unit="mm")
    t, y = ref.t, ref.y
    assert t[-1] == pytest.approx(1.0 + 8.0 + 1.5) and R.edge_jump(y) < 1e-6
    assert R.edge_jump(np.sin(2 * np.pi * t)) > 0.99                  # starts with its full slope
    assert np.all(y[t <= 1.0] == 0) and np.all(y[t >= 9.0] == 0)
    body = ref.body
    np.testing.assert_allclose(y[body], 0.3 * np.sin(2 * np.pi * (t[body] - 1.0)), atol=1e-12)
    assert t[body][0] == pytest.approx(3.0, abs=DT) and t[body][-1] == pytest.approx(7.0, abs=DT)
    # C2 at the joints: second differences stay O(dt^2), no kink (a kink gives O(dt))
    d2 = np.abs(np.diff(y, 2)) / DT**2
    assert np.max(d2) < 1.1 * 0.3 * (2 * np.pi) ** 2 * 3


def test_smootherstep_is_the_c2_ramp():
    x = np.linspace(0, 1, 11)
    np.testing.assert_allclose(R.smootherstep(x), 10 * x**3 - 15 * x**4 + 6 * x**5)
    assert R.smootherstep(-1.0) == 0.0 and R.smootherstep(2.0) == 1.0


def test_multitone_steps_and_file_roundtrip(tmp_path):
    m = R.multitone([0.2, 0.1], [0.5, 2.0], 10.0, 1 / DT, phases_deg=[0, 90])
    tb = m.t[m.body] - m.lead_s
    np.testing.assert_allclose(m.y[m.body], 0.2 * np.sin(np.pi * tb) + 0.1 * np.cos(4 * np.pi * tb), atol=1e-12)
    s = R.smoothed_steps([0.2, -0.1], 1.0, 1 / DT, transition_s=0.5)
    levels = np.round(s.y[np.r_[False, np.diff(s.y) == 0] & (s.y != 0)], 12)
    assert set(levels.tolist()) == {0.2, -0.1} and s.y[0] == 0 and s.y[-1] == 0
    path = m.save(tmp_path / "ref.csv")
    back = R.from_file(path)
    np.testing.assert_allclose(back.y, m.y, rtol=0, atol=1e-15)
    faded = R.from_file(path, fade_in_s=0.5, fade_out_s=0.5, lead_s=0.2)
    assert faded.t.size == m.t.size + 200
    m.save(tmp_path / "ref.npz")
    np.testing.assert_allclose(R.from_file(tmp_path / "ref.npz").y, m.y)


@pytest.mark.parametrize("call, match", [
    (lambda: R.sine(1, 600, 1, 1000), "below fs_hz/2"),
    (lambda: R.sine(1, 1, 1.0, 1000, fade_in_s=0.6, fade_out_s=0.6), "exceeds duration"),
    (lambda: R.multitone([1, 2], [1], 4, 1000), "as many"),
    (lambda: R.smoothed_steps([], 1, 1000), "non-empty"),
    (lambda: R.fade([0, 1, 3], [0, 1, 2], 0, 0), "uniformly"),
])
def test_bad_reference_input(call, match):
    with pytest.raises(IPMCError, match=match):
        call()


def test_feedforward_is_limited_to_3_V_unless_told_otherwise():
    """Safe by default: without ``limits`` a drive beyond 3 V (a printed constant here, not the
    library's) is refused; the inverse is linear, so scaling the reference scales the drive, which
    places the peak on either side of the limit without trusting the check under test."""
    from inversion import DEFAULT_MAX_VOLTAGE, InversionError, invert

    assert DEFAULT_MAX_VOLTAGE == 3.0
    G = toy_actuator()
    ref = R.sine(1.0, 1.0, 6.0, 1 / DT)
    unit_peak = float(np.max(np.abs(feedforward(G, ref.t, ref.y, limits="off").output)))
    over, under = ref.y * (4.0 / unit_peak), ref.y * (2.9 / unit_peak)       # 4 V and 2.9 V drives
    for given in ({}, {"limits": None}, {"limits": "default"}):
        with pytest.raises(LimitError, match=r"beyond max_voltage = ±3 V"):
            feedforward(G, ref.t, over, **given)
    ok = feedforward(G, ref.t, under)
    assert ok.limit_report.ok and ok.limit_report.peak == pytest.approx(2.9, rel=1e-9)
    assert ok.limit_report.limits == Limits(max_voltage=3.0)
    # dropping it takes an explicit word; the peaks are still measured
    for off in ("off", Limits()):
        r = feedforward(G, ref.t, over, limits=off)
        assert r.limit_report.ok and r.limit_report.peak == pytest.approx(4.0, rel=1e-9)
    assert feedforward(G, ref.t, over, limits="off").limit_report.limits is None
    # a model whose input is in mV: the default is 3000 mV
    assert feedforward(G, ref.t, over, input_unit="mV").limit_report.limits == Limits(max_voltage=3000.0)
    with pytest.raises(LimitError, match=r"beyond max_voltage = ±3000 mV"):
        feedforward(G, ref.t, over * 1000.0, input_unit="mV")
    with pytest.raises(InversionError, match="voltage unit"):
        feedforward(G, ref.t, under, input_unit="mm")
    with pytest.raises(InversionError, match="expected 'default'"):
        feedforward(G, ref.t, under, limits=False)
    # the generic inverse checks nothing (its output may be a displacement): no report
    assert invert(G, ref.t, over).limit_report is None


def test_unfaded_reference_spikes_at_the_end_faded_one_does_not():
    G = toy_actuator()
    faded = R.sine(1.0, 1.0, 6.0, 1 / DT, lead_s=2.0, tail_s=2.0)
    t = faded.t
    raw = np.where(t >= 2.0, np.sin(2 * np.pi * (t - 2.0) + 1.0), 0.0)    # starts and stops abruptly
    with pytest.raises(LimitError, match="beyond max_voltage = ±3 V"):     # the default 3 V limit
        feedforward(G, t, raw, preview="inf")
    v_raw = feedforward(G, t, raw, preview="inf", limits="off").output      # to look at the spike
    v_faded = feedforward(G, t, faded.y, preview="inf").output
    steady = np.max(np.abs(v_faded[faded.body]))
    assert np.max(np.abs(v_faded)) <= 1.01 * steady
    assert np.max(np.abs(v_raw)) > 3 * steady            # the jumps excite the inverse


# ------------------------------------------------------------------- reference files
def _old_csv(path, unit_suffix=""):
    """A file as the old ``Reference.save`` wrote it (written here by hand, not by the library)."""
    col = f"reference_{unit_suffix}" if unit_suffix else "reference"
    lines = ["# ipmc-reference 1", "# description: sine 0.3 at 1 Hz", "# fade_in_s: 2", "# fade_out_s: 2",
             "# lead_s: 1", "# tail_s: 1", f"time_s,{col}"]
    t = np.arange(6) * 0.25
    y = np.r_[0.0, 0.1, -0.2, 0.3, 0.05, 0.0]
    lines += [f"{float(a)!r},{float(b)!r}" for a, b in zip(t, y)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return t, y


def test_old_reference_files_stay_readable(tmp_path):
    t, y = _old_csv(tmp_path / "old.csv")
    back = R.from_file(tmp_path / "old.csv")
    np.testing.assert_array_equal(back.t, t)
    np.testing.assert_array_equal(back.y, y)
    assert back.unit == R.DEFAULT_UNIT == "m"                  # a unit-less column: the default unit
    assert R.from_file(tmp_path / "old.csv", unit="mm").unit == "mm"   # ... or the caller's
    _old_csv(tmp_path / "old_mm.csv", "mm")
    assert R.from_file(tmp_path / "old_mm.csv").unit == "mm"
    # the old NPZ: a JSON header of format 'ipmc-reference' without a version
    import json

    np.savez(tmp_path / "old.npz", header=np.array(json.dumps({"format": "ipmc-reference", "metadata": {"lead_s": "1"}})),
             time_s=t, reference=y)
    np.testing.assert_array_equal(R.from_file(tmp_path / "old.npz").y, y)


def test_saved_references_are_time_records_with_a_unit(tmp_path):
    from physmodel.data.timerecord import read_record

    ref = R.sine(0.3, 1.0, 4.0, 200.0)                           # no unit given
    rec = read_record(ref.save(tmp_path / "r.csv"))
    assert rec.units == {"reference": "m"} and rec.metadata["fade_in_s"] == "2"
    assert "# reference_m: reference [m]" in (tmp_path / "r.csv").read_text().splitlines()
    mm = R.sine(0.3, 1.0, 4.0, 200.0, unit="mm")
    for ext in ("csv", "npz", "mat"):
        back = R.from_file(mm.save(tmp_path / f"r.{ext}"))
        assert back.unit == "mm"
        np.testing.assert_array_equal(back.y, mm.y)
    # a column in another unit of the same kind is converted, of another kind refused
    um = R.from_file(tmp_path / "r.csv", unit="um")
    np.testing.assert_allclose(um.y, mm.y * 1e3, rtol=1e-15)
    with pytest.raises(IPMCError, match="cannot be converted"):
        R.from_file(tmp_path / "r.csv", unit="V")
    with pytest.raises(IPMCError, match="no column 'target'"):
        R.from_file(tmp_path / "r.csv", column="target")
    with pytest.raises(IPMCError, match="unknown time-record file type"):
        mm.save(tmp_path / "r.txt")
