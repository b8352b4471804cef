"""A model zero the sampling cannot represent is treated as at infinity (inversion.split, "Zeros at
infinity"): the reviewer's case of a temperature schedule whose zero coefficient beta passes through
0, so that the zero of (1 + beta s) goes through infinity from one half-plane to the other.

Before the fix, a zero at s = +1e13 rad/s inverted at dt = 1 ms gave a peak of 8e7 (true answer
about 1.9) with no complaint, and at s = -1e13 a finite answer, while beta = 0 exactly was refused
as strictly proper.  Now all three take the beta = 0 path.
"""

import math
import re
import subprocess
import sys
from pathlib import Path

import mpmath as mp
import numpy as np
import pytest

from inversion import (
    ImproperInverseError,
    InversionError,
    StreamingInverter,
    ZeroAtInfinityWarning,
    feedforward,
    invert,
    invert_scheduled,
    invert_to,
    split_inverse,
)
from inversion.preview import DEFAULT_PREVIEW_TOL
from inversion.split import ZERO_AT_INFINITY_RTOL, zeros_beyond_sampling

DT = 1e-3
NYQ = math.pi / DT
# the reviewer's model at the critical temperature: k (1 + b1 s + b2 s^2)(1 + beta s) / D(s),
# k = 2, b1 = -0.3, b2 = 0.2 (a right half-plane pair at 0.75 +- 2.1j), D from the surrogate file
DEN = np.array([1.0, 2.326574, 2.349859, 1.221403])
BASE = 2.0 * np.array([0.2, -0.3, 1.0])
GIANT = (1e13, -1e13, 1e9, -1e9)
WF = 2 * np.pi * 20.0          # filter bandwidth [rad/s] for improper="filter"


def _num(z):
    """BASE * (1 - s/z): one more zero, at s = z, with the same low-frequency gain."""
    return np.polymul(BASE, [-1.0 / z, 1.0])


def _signal(duration=4.0):
    t = np.arange(int(round(duration / DT)) + 1) * DT
    return t, 0.1 * np.sin(2 * np.pi * t)


@pytest.mark.parametrize("z", GIANT)
def test_giant_zero_is_refused_like_no_zero(z):
    t, u = _signal()
    with pytest.raises(ImproperInverseError) as none_exc:
        invert((BASE, DEN), DT, u)
    with pytest.raises(ImproperInverseError) as exc:
        invert((_num(z), DEN), DT, u)
    msg = str(exc.value)
    assert f"|z| = {abs(z):.3g} rad/s" in msg and "treated as at infinity" in msg
    assert "improper='filter'" in msg and "improper='differentiate'" in msg
    assert "treated as at infinity" not in str(none_exc.value)


@pytest.mark.parametrize("improper", ["filter", "differentiate"])
@pytest.mark.parametrize("z", GIANT)
def test_giant_zero_gives_the_no_zero_answer(z, improper):
    t, u = _signal()
    kw = {"improper": improper, "preview": "inf"}
    if improper == "filter":
        kw["filter_bandwidth"] = WF
    ref = invert((BASE, DEN), DT, u, **kw)
    words = re.escape(f"|z| = {abs(z):.3g} rad/s") + ".*" + re.escape(f"improper='{improper}' applies")
    with pytest.warns(ZeroAtInfinityWarning, match=words):
        res = invert((_num(z), DEN), DT, u, **kw)
    # dropping the factor changes the model by at most (pi/dt)/|z| at any representable frequency
    tol = NYQ / abs(z) * float(np.max(np.abs(ref.output)))
    assert np.max(np.abs(res.output - ref.output)) <= tol
    np.testing.assert_allclose(res.split.zeros_at_infinity, [z], rtol=1e-9)
    assert len(res.notes) == 1 and f"|z| = {abs(z):.3g} rad/s" in res.notes[0]
    assert res.split.sampling_interval == DT
    assert ref.notes == ()
    # the reviewer's figure: about 1.87 peak, not 8e7
    assert 1.5 < np.max(np.abs(res.output)) < 2.5


def test_deflation_against_the_factors_it_was_built_from():
    # independent of np.roots: BASE is what num was multiplied from, exactly representable factors
    for z in GIANT:
        num = _num(z)
        out, dropped = zeros_beyond_sampling(num, DT)
        assert dropped.size == 1
        np.testing.assert_allclose(out, BASE, rtol=4 * np.finfo(float).eps, atol=0)
    # a complex pair at infinity (|z| = 1e12 rad/s) goes as a pair, the real quadratic factor
    p = 1e12 * np.exp(1j * 2.0)
    quad = np.real(np.poly([p, np.conj(p)])) / abs(p) ** 2         # (1 - s/p)(1 - s/p*)
    out, dropped = zeros_beyond_sampling(np.polymul(BASE, quad), DT)
    assert dropped.size == 2
    np.testing.assert_allclose(out, BASE, rtol=1e-14, atol=0)


def test_filtered_answer_against_mpmath_steady_state():
    """Independent oracle: the continuous filtered inverse of the no-zero model at 1 Hz, in mpmath,
    against the middle of a long record inverted with the zero at s = +1e13 rad/s."""
    t, u = _signal(60.0)
    with pytest.warns(ZeroAtInfinityWarning):
        res = invert((_num(1e13), DEN), DT, u, improper="filter", filter_bandwidth=WF, preview="inf")
    w = 2 * np.pi
    s = mp.mpc(0, w)
    def horner(coeffs, x):          # descending powers; mp.polyval's order keyword differs across mpmath versions
        acc = mp.mpf(0)
        for c in coeffs:
            acc = acc * x + mp.mpf(c)
        return acc

    H = (horner(DEN, s) / horner(BASE, s)
         * WF / (s + WF))
    ref = 0.1 * np.imag(complex(H) * np.exp(1j * w * t))
    mid = (t > 20) & (t < 40)
    err = float(np.max(np.abs(res.output[mid] - ref[mid])))
    # FOH discretisation bound of inversion._discrete (||h||_1 dt^2/8 max|u''|, as the result
    # estimates it) plus what is left of the anticausal end transient 20 s before the end
    # (slowest anticausal pole Re = 0.75 1/s; the transient is at most the output's peak)
    edge = math.exp(-0.75 * 20.0) * float(np.max(np.abs(res.output)))
    assert err <= res.discretisation_error_estimate + edge
    assert err < 1e-3 * float(np.max(np.abs(ref)))


@pytest.mark.parametrize("zdt", [-0.5, 1.0, -10 * math.pi, 10 * math.pi, 100.0, -100.0, -3000.0])
def test_representable_zero_is_kept_bit_for_bit(zdt):
    """|z| dt from 0.5 to 3000 (below pi/ZERO_AT_INFINITY_RTOL = 3142): the zero is kept and the
    answer is bit for bit the one of the split built without dt (the code path before the rule)."""
    assert math.pi / abs(zdt) > ZERO_AT_INFINITY_RTOL
    z = zdt / DT
    t, u = _signal()
    model = (_num(z), DEN)
    res = invert(model, DT, u, preview="inf")
    assert res.split.zeros_at_infinity.size == 0 and res.notes == ()
    old = invert(split_inverse(model), DT, u, preview="inf")
    assert np.array_equal(res.output, old.output)
    assert np.any(np.isclose(res.split.zeros, z, rtol=1e-9))


def test_criterion_boundary_follows_the_stated_tolerance():
    assert ZERO_AT_INFINITY_RTOL == DEFAULT_PREVIEW_TOL          # as inversion.split documents
    for factor, dropped in ((0.99, False), (1.01, True)):
        z = -factor * NYQ / ZERO_AT_INFINITY_RTOL            # (pi/dt)/|z| = tol / factor
        _, d = zeros_beyond_sampling(_num(z), DT)
        assert (d.size == 1) is dropped


@pytest.mark.filterwarnings("ignore::inversion.ZeroAtInfinityWarning")
def test_streaming_scheduled_and_chunked_paths_drop_it_too():
    t, u = _signal()
    kw = {"improper": "filter", "filter_bandwidth": WF}
    ref = invert((BASE, DEN), DT, u, preview=0.5, **kw).output
    for z in (1e13, -1e13):
        model = (_num(z), DEN)
        inv = StreamingInverter(model, DT, preview=0.5, **kw)
        y = np.concatenate([inv.push(u[:1500]), inv.push(u[1500:]), inv.flush()])
        assert inv.split.zeros_at_infinity.size == 1
        tol = NYQ / abs(z) * float(np.max(np.abs(ref)))
        assert np.max(np.abs(y - ref)) <= tol + 1e-12 * float(np.max(np.abs(ref)))
        out = np.zeros_like(u)
        invert_to(model, DT, u, out, preview=0.5, chunk_size=1000, **kw)
        assert np.max(np.abs(out - ref)) <= tol + 1e-12 * float(np.max(np.abs(ref)))
        ff = feedforward(model, DT, u, preview=0.5, limits="off", **kw)
        assert ff.notes and np.max(np.abs(ff.output - ref)) <= tol
    # a schedule whose zero passes through infinity between -1 and 1 degC: beta = T * 1e-13
    def model_at(T):
        beta = T * 1e-13
        return (np.polymul(BASE, [beta, 1.0]) if beta else BASE, DEN)
    temp = np.linspace(-1.0, 1.0, u.size)
    with pytest.raises(ImproperInverseError, match=r"model_at\(-1 degC\).*treated as at infinity"):
        invert_scheduled(model_at, DT, u, temp)
    sched = invert_scheduled(model_at, DT, u, temp, preview=0.5, **kw)
    assert all(sp.num.size == sched.splits[1].num.size for sp in sched.splits)   # same path for all
    assert [sp.zeros_at_infinity.size for sp in sched.splits] == [1, 0, 1]
    assert [n.split(":")[0] for n in sched.notes] == ["-1 degC", "1 degC"]
    assert np.max(np.abs(sched.output - ref)) <= 1e-9 * float(np.max(np.abs(ref)))


def test_a_split_built_for_other_sampling_is_not_used_silently():
    t, u = _signal()
    model = (_num(-1e13), DEN)
    with pytest.raises(InversionError, match=r"split_inverse\(model, dt=0.001\)"):
        invert(split_inverse(model), DT, u)       # built without dt: keeps the zero
    with pytest.warns(ZeroAtInfinityWarning):
        sp = split_inverse((_num(-1e9), DEN), dt=DT, improper="filter", filter_bandwidth=WF)
    assert sp.zeros_at_infinity.size == 1
    with pytest.raises(InversionError, match="representable"):
        invert(sp, 1e-7, u)                      # |z| dt = 100 there: not at infinity
    res = invert(sp, DT, u)                      # the dt it was built for
    assert res.notes == sp.notes


def _surrogate_json(path, beta):
    """The reviewer's 3-zero/3-pole zpk surrogate (schema 2) with the real zero section (1 + beta s)."""
    doc = {
        "schema": "ipmc.surrogate.rational_model", "schema_version": 2,
        "structure": {"form": "zpk", "n_zeros": 3, "n_poles": 3, "degree": 0, "zero_sections": "unit"},
        "scaling": {"omega_ref_rad_s": 1.0, "gain_ref": 1.0, "temperature_center_c": 0.0,
                    "temperature_scale_c": 1.0},
        "temperature_range_c": [-1.0, 1.0],
        "params": {"names": ["k", "zb1_0", "zb2_0", "zb", "log_a1_0", "log_a0_0", "log_c"],
                   "values": [2.0, -0.3, 0.2, beta, 0.1, 0.0, 0.2], "covariance": None},
        "labels": {}, "info": {},
        "conventions": {"s": "rad/s", "frequency_edges": "Hz", "temperature": "degC",
                        "model": "H = gain_ref*N(s/omega_ref, tau)/D(s/omega_ref, tau), "
                                 "tau = (T - temperature_center_c)/temperature_scale_c"},
    }
    import json

    path.write_text(json.dumps(doc))
    return path


def test_cli_refuses_or_says_it(tmp_path, capsys):
    """``ipmc invert`` on the reviewer's files: exit 2 naming the zero and the option; with a filter
    exit 0, the reviewer's 1.87 peak, and the dropped zero said on stderr."""
    from scenarios.cli import main

    t, u = _signal()
    sig = tmp_path / "sig.csv"
    with open(sig, "w") as fh:
        fh.write("time_s,y\n")
        np.savetxt(fh, np.column_stack([t, u]), delimiter=",", fmt="%.17g")
    for beta in (-1e-13, 1e-13):
        model = _surrogate_json(tmp_path / f"zb_{beta}.json", beta)
        out = tmp_path / "out.csv"
        argv = ["invert", str(sig), "--surrogate", str(model), "--temperature", "0", "-o", str(out), "--quiet"]
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "|z| = 1e+13 rad/s" in err and "--improper filter" in err and not out.exists()
        with pytest.warns(ZeroAtInfinityWarning, match=re.escape("|z| = 1e+13 rad/s")):
            assert main([*argv, "--improper", "filter", "--filter-bandwidth", str(WF)]) == 0
        lines = out.read_text().splitlines()
        assert any(ln.startswith("# inversion_note:") and "treated as at infinity" in ln for ln in lines), lines[:5]
        body = [ln for ln in lines if not ln.startswith("#")][1:]          # below the column names
        y = np.loadtxt(body, delimiter=",")[:, 2]
        assert 1.5 < np.max(np.abs(y)) < 2.5
        out.unlink()
    # as a user sees it (pytest records warnings instead of printing them): one line on stderr
    root = Path(__file__).resolve().parents[2]
    proc = subprocess.run(
        [sys.executable, "-c", "import sys; from scenarios.cli import main; sys.exit(main(sys.argv[1:]))",
         *argv, "--improper", "filter", "--filter-bandwidth", str(WF)],
        capture_output=True, text=True, cwd=root, env={"PYTHONPATH": str(root), "OMP_NUM_THREADS": "1",
                                                      "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"})
    assert proc.returncode == 0, proc.stderr
    assert "ipmc invert: warning: the model's zero at s = -1e+13" in proc.stderr
    assert "treated as at infinity" in proc.stderr


def test_choose_preview_checks_the_split_too():
    from inversion import choose_preview

    t, u = _signal()
    with pytest.raises(InversionError, match=r"split_inverse\(model, dt=0.001\)"):
        choose_preview(split_inverse((_num(-1e13), DEN)), DT, u)
