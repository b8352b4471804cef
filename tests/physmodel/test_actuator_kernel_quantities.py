"""The actuator kernel computes only what the requested quantities need, and rows that share the
electrode line or slice with the first set share those terms: every quantity, alone or with
others, must equal bit for bit the kernel as it was before (issue 17, commit 9715fa4), which is
kept below verbatim as the reference."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from physmodel import ActuatorModel, beam, electrode, get_parameter_set, transport
from physmodel.actuator import LINE_FIELDS, SLICE_FIELDS, actuator_kernel, shared_rows, shared_sets
from physmodel.model import PhysicsModel
from physmodel.params import STATE_FIELDS, state_at


def reference_kernel(p, s, quantities=("Z", "H", "G", "M")) -> dict:
    """physmodel.actuator.actuator_kernel at 9715fa4 (every strip term computed for any quantity)."""
    K = p["K"]
    W, h, L = p["W"], p["h"], p["L"]
    want_z = "Z" in quantities or "I" in quantities
    c, frac, A, X, xcoth = electrode.strip_terms(p, s, want_xcoth=want_z)
    out = {}
    if want_z:
        Z = electrode.terminal_impedance(A, L, xcoth)
        if "Z" in quantities:
            out["Z"] = Z
        if "I" in quantities:
            out["I"] = 1.0 / Z
    need_g = "G" in quantities or "M" in quantities
    wn = p["omega_n"]
    if need_g:
        gden = s + 2.0 * p["xi"] * wn
        gden *= s
        gden += wn * wn
    if "G" in quantities:
        out["G"] = (wn * wn) / gden
    if "H" in quantities or "M" in quantities:
        gain = -(L * L) / (p["E"] * beam.second_moment(W, h)) * (p["alpha0"] * W * p["kappa_e"] * K)
        H = c.gmt / c.den
        H *= X
        H *= frac
        if "H" in quantities:
            out["H"] = H * gain
        if "M" in quantities:
            H /= gden
            H *= gain * wn * wn
            out["M"] = H
    return out


QUANTITY_SETS = [qs for n in range(1, 6) for qs in itertools.combinations(ActuatorModel.quantities, n)]


def _batch():
    """Sets like a calibration's finite-difference rows: some repeat an earlier set's line or slice
    (xi, E: the mode and gain only; r1_sheet: the line only), others move the charge dynamics."""
    b = get_parameter_set("seed002_table3")
    sets = [b, b.replace(xi=0.3), b.replace(d=b.d * 2), b.replace(E=b.E * 1.1), b,
            b.replace(r1_sheet=b.r1_sheet * 3), b.replace(alpha0=b.alpha0 * 2), b.replace(kappa_e=b.kappa_e * 0.7),
            b.replace(r2_specific=b.r2_specific * 2 + 1e-4), b.replace(d=b.d * 2, xi=0.5),
            b.replace(d=b.d * 2, r1_sheet=b.r1_sheet * 3)]
    return state_at(sets, [5.0, 25.0, 60.0])


@pytest.mark.parametrize("qs", QUANTITY_SETS, ids="".join)
def test_kernel_equals_the_reference_bit_for_bit(qs):
    st = _batch()
    n = st.T.shape[0] * st.T.shape[1]
    p = {k: getattr(st, k).reshape(n)[:, None] for k in STATE_FIELDS}
    s = 2j * np.pi * np.logspace(-3, 5, 41)[None, :]
    ref = reference_kernel(p, s, qs)
    shared = shared_rows(st)
    assert shared is not None and shared[0] is not None and shared[1] is not None
    for got in (actuator_kernel(p, s, qs), actuator_kernel(p, s, qs, shared)):
        assert sorted(got) == sorted(qs)
        for q in qs:
            assert got[q].shape == ref[q].shape
            assert np.array_equal(got[q], ref[q]), q
    # scalar parameters (the long-row path of evaluate_grid)
    ps = {k: v[4, 0] for k, v in p.items()}
    ref1, got1 = reference_kernel(ps, s[0], qs), actuator_kernel(ps, s[0], qs)
    assert all(np.array_equal(got1[q], ref1[q]) for q in qs)


def test_the_mode_alone_needs_no_charge_dynamics(monkeypatch):
    def refuse(*a, **k):
        raise AssertionError("charge dynamics evaluated for G alone")

    monkeypatch.setattr(transport, "charge_terms", refuse)
    st = _batch()
    p = {k: getattr(st, k).reshape(-1)[:, None] for k in STATE_FIELDS}
    G = actuator_kernel(p, 2j * np.pi * np.array([[1.0, 10.0]]), ("G",))["G"]
    wn, xi, s = p["omega_n"], p["xi"], 2j * np.pi * np.array([[1.0, 10.0]])
    assert np.allclose(G, wn**2 / (s**2 + 2 * xi * wn * s + wn**2), rtol=1e-14, atol=0)


@pytest.mark.parametrize("qs", [("M",), ("Z", "I"), ("H", "G"), ActuatorModel.quantities], ids="".join)
def test_evaluate_state_equals_the_generic_grid(qs):
    st = _batch()
    m = ActuatorModel(get_parameter_set("seed002_table3"))
    s = 2j * np.pi * np.logspace(-1, 3, 30)
    fast, generic = m.evaluate_state(st, s, qs), PhysicsModel.evaluate_state(m, st, s, qs)
    for q in qs:
        assert fast[q].shape == (st.T.shape[0], st.T.shape[1], s.size)
        assert np.array_equal(fast[q], generic[q])
    # a batch with nothing shared, and one set: the generic path
    one = state_at([get_parameter_set("seed002_table3")], [25.0])
    assert shared_rows(one) is None
    assert np.array_equal(m.evaluate_state(one, s, ("M",))["M"], m.evaluate(s, [25.0], ("M",))["M"])


def test_evaluate_state_refuses_unknown_quantities():
    from physmodel.errors import IPMCError

    m = ActuatorModel(get_parameter_set("seed002_table3"))
    with pytest.raises(IPMCError, match="unknown quantity"):
        m.evaluate_state(_batch(), np.array([1j]), ("S",))


def _first_identical(state, fields, sets):
    """For each of ``sets`` the position (in ``sets``) of the first set with the same values of
    ``fields`` at every temperature: a plain double loop with np.array_equal (the oracle of
    shared_rows' grouping)."""
    out = []
    for j, i in enumerate(sets):
        out.append(next(k for k, i2 in enumerate(sets)
                        if all(np.array_equal(getattr(state, f)[i2], getattr(state, f)[i]) for f in fields)))
    return out


def _decode(level, n_sets_or_kept, n_T):
    """(first rows, inverse) of one level of ``shared`` back to set indices."""
    first, inverse = level
    return first.reshape(-1, n_T)[:, 0] // n_T, inverse.reshape(-1, n_T)[:, 0] // n_T


def test_shared_rows_groups_the_sets_an_independent_loop_groups():
    st = _batch()
    n_sets, n_T = st.T.shape[:2]
    (line, sl) = shared_rows(st)
    first = _first_identical(st, LINE_FIELDS, list(range(n_sets)))
    kept = sorted(set(first))
    rows, inv = _decode(line, n_sets, n_T)
    assert rows.tolist() == kept and [kept[k] for k in inv] == first
    first_s = _first_identical(st, SLICE_FIELDS, kept)
    kept_s = sorted(set(first_s))
    rows_s, inv_s = _decode(sl, len(kept), n_T)
    assert rows_s.tolist() == kept_s and [kept_s[k] for k in inv_s] == first_s
    # the fields that do not differ between sets need not be compared: the same grouping
    differ = [f for f in LINE_FIELDS if not all(np.array_equal(getattr(st, f)[i], getattr(st, f)[0])
                                                for i in range(n_sets))]
    assert 0 < len(differ) < len(LINE_FIELDS)
    got = shared_sets({f: getattr(st, f) for f in LINE_FIELDS}, n_sets, n_T, differ)
    for a, b in zip(got, (line, sl)):
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])


@pytest.mark.parametrize("qs", [("M",), ("Z", "I"), ActuatorModel.quantities], ids="".join)
def test_evaluate_columns_equals_evaluate_state_bit_for_bit(qs):
    st = _batch()
    n_sets, n_T = st.T.shape[:2]
    m = ActuatorModel(get_parameter_set("seed002_table3"))
    s = 2j * np.pi * np.logspace(-1, 3, 30)
    p = {k: np.ascontiguousarray(getattr(st, k).reshape(-1))[:, None] for k in STATE_FIELDS}
    for k in p.values():
        k.flags.writeable = False           # the columns are only read
    ref = m.evaluate_state(st, s, qs)
    # only the fields that differ between sets named: the others are taken without a gather
    differ = [f for f in STATE_FIELDS if not np.array_equal(getattr(st, f), np.broadcast_to(getattr(st, f)[:1],
                                                                                           getattr(st, f).shape))]
    assert {"d", "r1", "r2"} <= set(differ) and "L" not in differ
    for got in (m.evaluate_columns(p, n_sets, n_T, s, qs), m.evaluate_columns(p, n_sets, n_T, s, qs, differ)):
        for q in qs:
            assert np.array_equal(got[q], ref[q]), q
    # one set: the generic path, as evaluate_state takes it
    one = {k: v[:n_T] for k, v in p.items()}
    first = type(st)(**{k: getattr(st, k)[:1] for k in STATE_FIELDS})
    assert np.array_equal(m.evaluate_columns(one, 1, n_T, s, ("M",))["M"], m.evaluate_state(first, s, ("M",))["M"])
