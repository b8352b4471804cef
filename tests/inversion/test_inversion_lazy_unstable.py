"""``InversionResult.unstable_part`` is recomputed when first read whenever the anticausal pass
ran block by block (issue 29: not writing it saves a record-sized array on every inversion), and
so is ``stable_part``, over which the output is then written (one more array saved).

Oracles: the plan run with the anticausal part kept (the code path as it was before), and, for
the output itself, the explicit state recursions of the FOH discretisation (forward for the
stable part, the finite-preview window sum of seed 000 eq. (6) backward for the anticausal
part) with ``scipy.linalg.expm`` — independent of the filters, of ``expm_small`` and of the
block structure.
"""

import numpy as np
import pytest
import scipy.linalg as sla

from inversion import InversionError, NonFiniteSignalError, invert, split_inverse
from inversion._discrete import plan_for
from inversion.examples import seed000_sensor_35c

G35 = seed000_sensor_35c("coefficients")


def _foh(M, B, dt):
    m = M.shape[0]
    big = np.zeros((m + 2, m + 2))
    big[:m, :m], big[:m, m], big[m, m + 1] = M * dt, B * dt, 1.0
    E = sla.expm(big)
    alpha = E[:m, m + 1]
    return E[:m, :m], alpha, E[:m, m] - alpha


def _explicit_inverse(split, dt, n_prev, u):
    """stable + anticausal parts by explicit state recursions (u = 0 outside the record)."""
    n = u.size
    Phi, al, be = _foh(split.A_s, split.B_s, dt)
    x = np.zeros(split.n_stable)
    up = np.concatenate(([0.0], u))
    ys = np.empty(n)
    for k in range(n):
        x = Phi @ x + al * up[k + 1] + be * up[k]
        ys[k] = split.C_s @ x + split.feedthrough * u[k]
    Phi, al, be = _foh(-split.A_u, split.B_u, dt)
    m = Phi.shape[0]
    un = np.append(u, 0.0)
    xs = np.zeros((n + n_prev + 1, m))
    for k in range(n - 1, -1, -1):
        xs[k] = Phi @ xs[k + 1] + al * un[k] + be * un[k + 1]
    xbar = xs[:n] - xs[n_prev:n_prev + n] @ np.linalg.matrix_power(Phi, n_prev).T
    return ys, xbar @ (-split.C_u)


def _signal(n, seed):
    rng = np.random.default_rng(seed)
    return np.sin(2 * np.pi * 20e-3 * np.arange(n)) + 0.1 * rng.standard_normal(n)


@pytest.mark.parametrize("fs, chunk", [(1e3, None), (20e3, None), (1e3, 700)])
def test_recomputed_unstable_part_is_the_kept_one_bit_for_bit(fs, chunk):
    split = split_inverse(G35)
    dt = 1.0 / fs
    n_prev = round(split.auto_preview_s / dt)
    u = _signal(3 * n_prev + 1234, 5)
    res = invert(split, dt, u, preview=n_prev * dt, chunk_size=chunk)
    assert not isinstance(res.unstable_source, np.ndarray)     # not stored: recomputed below
    stable, unstable, output = plan_for(split, dt, n_prev).run(u, chunk or u.size, keep_unstable=True)
    np.testing.assert_array_equal(res.output, output)
    np.testing.assert_array_equal(res.stable_part, stable)
    np.testing.assert_array_equal(res.unstable_part, unstable)
    np.testing.assert_array_equal(res.stable_part + res.unstable_part, res.output)


def test_automatic_preview_recomputes_the_same_unstable_part():
    split = split_inverse(G35)
    u = _signal(6000, 6)
    res = invert(split, 1e-3, u, preview="auto")
    N = res.preview_samples
    kept = plan_for(split, 1e-3, N).run(u, u.size, keep_unstable=True)
    np.testing.assert_array_equal(res.unstable_part, kept[1])
    np.testing.assert_array_equal(res.output, kept[2])


def test_output_equals_the_explicit_state_recursions():
    split = split_inverse(G35)
    dt, n_prev = 1e-3, 113
    u = _signal(2500, 7)
    ys, yu = _explicit_inverse(split, dt, n_prev, u)
    res = invert(split, dt, u, preview=n_prev * dt)
    scale = np.max(np.abs(ys + yu))
    np.testing.assert_allclose(res.output, ys + yu, rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(res.unstable_part, yu, rtol=0, atol=1e-11 * scale)


def test_modifying_the_input_before_reading_the_unstable_part_is_refused():
    split = split_inverse(G35)
    u = _signal(2000, 8)
    res = invert(split, 1e-3, u, preview=0.113)
    assert res.input is u                     # the caller's own array, not a copy
    u[1500] += 1.0
    with pytest.raises(InversionError, match="modified in place"):
        _ = res.unstable_part


def test_chunked_infinite_preview_recomputes_the_same_unstable_part():
    split = split_inverse(G35)
    u = _signal(2000, 10)
    res = invert(split, 1e-3, u, preview="inf", chunk_size=300)
    assert not isinstance(res.unstable_source, np.ndarray)
    kept = plan_for(split, 1e-3, None).run(u, 300, keep_unstable=True)
    np.testing.assert_array_equal(res.unstable_part, kept[1])
    np.testing.assert_array_equal(res.output, kept[2])
    whole = invert(split, 1e-3, u, preview="inf")
    np.testing.assert_allclose(res.unstable_part, whole.unstable_part, rtol=0,
                               atol=1e-13 * np.max(np.abs(whole.output)))


def test_whole_record_infinite_preview_keeps_its_unstable_part():
    # one whole-record backward pass: its output is the anticausal part, kept as it is
    split = split_inverse(G35)
    u = _signal(2000, 9)
    res = invert(split, 1e-3, u, preview="inf")
    assert isinstance(res.unstable_source, np.ndarray)
    np.testing.assert_array_equal(res.stable_part + res.unstable_part, res.output)


@pytest.mark.parametrize("preview", [0.3, "auto", "inf"])
@pytest.mark.parametrize("chunk", [None, 700])
def test_an_overflowing_inverse_is_refused_on_every_path(preview, chunk):
    # the output's finiteness is proved from its sum taken block by block during the pass: an
    # inverse gain of 1e10 on a 1e300 signal must still be caught, and named
    G = ([1e-10, -5e-10], [1.0, 10.0])
    u = np.random.default_rng(0).standard_normal(5000) * 1e300
    with pytest.raises(NonFiniteSignalError, match="the inverse overflowed: output sample"):
        invert(G, 1e-3, u, preview=preview, chunk_size=chunk)


@pytest.mark.parametrize("preview", [0.113, "auto"])
@pytest.mark.parametrize("chunk", [None, 700])
def test_the_output_is_written_over_the_causal_part_which_is_recomputed_when_read(preview, chunk):
    # block by block the output is written over the causal part's array (one record-sized array
    # fewer); both parts are recomputed when read.  Oracle: the explicit state recursions.
    split = split_inverse(G35)
    dt = 1e-3
    u = _signal(2600, 11)
    res = invert(split, dt, u, preview=preview, chunk_size=chunk)
    assert res.stable_source is None and not isinstance(res.unstable_source, np.ndarray)
    ys, yu = _explicit_inverse(split, dt, res.preview_samples, u)
    scale = np.max(np.abs(ys + yu))
    np.testing.assert_allclose(res.stable_part, ys, rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(res.unstable_part, yu, rtol=0, atol=1e-11 * scale)
    np.testing.assert_array_equal(res.stable_part + res.unstable_part, res.output)


def test_automatic_preview_recomputes_the_parts_from_the_callers_array_and_refuses_a_changed_one():
    # preview='auto' keeps no copy of the signal (issue 29): the parts come from the caller's array,
    # the same bits as those of an untouched copy while it is unchanged, refused once it changed
    split = split_inverse(G35)
    u = _signal(2600, 12)
    ref = invert(split, 1e-3, u.copy())
    res, later = invert(split, 1e-3, u), invert(split, 1e-3, u)
    assert res.input is u and later.input is u
    np.testing.assert_array_equal(res.stable_part, ref.stable_part)
    np.testing.assert_array_equal(res.unstable_part, ref.unstable_part)
    u *= 100.0
    np.testing.assert_array_equal(res.unstable_part, ref.unstable_part)     # read before: kept
    with pytest.raises(InversionError, match="input array was modified in place"):
        _ = later.unstable_part


# the review's reproduction (issue 29): a nonminimum-phase model (zeros 1 +- 2j), dt 1 ms, 4000 samples,
# previews 0.5 s / inf / auto x whole record / chunks of 1000
G_NMP = ([1.0, -2.0, 5.0], [1.0, 3.0, 4.0])
PREVIEWS = [0.5, "inf", "auto"]
CHUNKS = [None, 1000]


def _windowed_sine():
    t = np.arange(4000) * 1e-3
    return np.sin(2 * np.pi * 3 * t) * np.hanning(t.size)


@pytest.mark.parametrize("preview", PREVIEWS)
@pytest.mark.parametrize("chunk", CHUNKS)
def test_editing_the_output_leaves_the_parts_readable_and_unchanged(preview, chunk):
    # clipping a drive in place must not break reading the parts.  Oracle: the parts of a fresh
    # inversion of an untouched copy of the input (with the anticausal part kept: infinite preview
    # whole-record keeps both parts, the others are compared with their own fresh recomputation)
    u = _windowed_sine()
    fresh = invert(G_NMP, 1e-3, u.copy(), preview=preview, chunk_size=chunk)
    ref_s, ref_u, ref_o = fresh.stable_part.copy(), fresh.unstable_part.copy(), fresh.output.copy()
    res = invert(G_NMP, 1e-3, u, preview=preview, chunk_size=chunk)
    np.testing.assert_array_equal(res.output, ref_o)
    assert np.max(np.abs(res.output)) > 0.2                     # the clip below changes the output
    res.output[:] = np.clip(res.output, -0.1, 0.1)
    np.testing.assert_array_equal(res.stable_part, ref_s)
    np.testing.assert_array_equal(res.unstable_part, ref_u)
    np.testing.assert_array_equal(ref_s + ref_u, ref_o)


@pytest.mark.parametrize("preview", PREVIEWS)
@pytest.mark.parametrize("chunk", CHUNKS)
def test_reusing_the_input_array_is_refused_or_harmless_on_every_path(preview, chunk):
    # what each path does when the caller overwrites its input array before reading the parts:
    # the whole-record infinite preview kept both; every other path ('auto' included, issue 29:
    # it keeps no copy) recomputes from the caller's array and refuses a changed one (found from
    # the output's sum, not from the output), and so do 'auto''s truncation errors
    u = _windowed_sine()
    fresh = invert(G_NMP, 1e-3, u.copy(), preview=preview, chunk_size=chunk)
    res = invert(G_NMP, 1e-3, u, preview=preview, chunk_size=chunk)
    res.output[:] = 0.0                      # not what the check reads: the refusal must still come
    u[:] = 0.0
    if preview == "inf" and chunk is None:
        np.testing.assert_array_equal(res.stable_part, fresh.stable_part)
        np.testing.assert_array_equal(res.unstable_part, fresh.unstable_part)
    else:
        with pytest.raises(InversionError, match="input array was modified in place"):
            _ = res.stable_part
        with pytest.raises(InversionError, match="input array was modified in place"):
            _ = res.unstable_part
    if preview == "auto":
        with pytest.raises(InversionError, match="input array was modified in place"):
            _ = res.preview_choice.relative_error


@pytest.mark.parametrize("preview, chunk", [(0.5, None), (0.5, 1000), ("inf", 1000), ("auto", None),
                                            ("auto", 1000)])
def test_one_changed_input_sample_is_refused(preview, chunk):
    # the paths that recompute from the caller's array (whole-record 'inf' keeps both parts)
    u = _windowed_sine()
    res = invert(G_NMP, 1e-3, u, preview=preview, chunk_size=chunk)
    u[2345] += 1e-6
    with pytest.raises(InversionError, match="modified in place"):
        _ = res.stable_part
    if preview == "auto":
        with pytest.raises(InversionError, match="modified in place"):
            _ = res.preview_choice.max_error


@pytest.mark.parametrize("chunk", CHUNKS)
def test_automatic_preview_keeps_the_callers_array_as_its_input_and_checks_it(chunk):
    # no copy (issue 29): input is the caller's array, writable; what is read later from it is the
    # same bits as for an untouched copy while it is unchanged, and refused once it changed (never
    # the errors of another signal: the review's reused buffer, 100x once)
    u = _windowed_sine()
    fresh = invert(G_NMP, 1e-3, u.copy(), chunk_size=chunk)
    res = invert(G_NMP, 1e-3, u, chunk_size=chunk)
    assert res.input is u and res.input.flags.writeable
    c, f = res.preview_choice, fresh.preview_choice
    assert (c.relative_error, c.max_error, c.error_bound) == (f.relative_error, f.max_error, f.error_bound)
    assert c.relative_error > 0
    assert res.truncation_error == fresh.truncation_error
    later = invert(G_NMP, 1e-3, u, chunk_size=chunk)
    u *= 100.0
    for name in ("relative_error", "max_error", "error_bound"):
        with pytest.raises(InversionError, match="input array was modified in place"):
            getattr(later.preview_choice, name)
    with pytest.raises(InversionError, match="input array was modified in place"):
        _ = later.truncation_error
    # read before the change: kept; the bound is the choice's, taken at the inversion
    assert res.preview_choice.relative_error == fresh.preview_choice.relative_error
    assert later.truncation_bound == fresh.truncation_bound > 0
    # not checked (documented): the sampling-error estimate is of the array as it is when read
    assert later.discretisation_error_estimate == pytest.approx(100 * fresh.discretisation_error_estimate,
                                                                rel=1e-12)


@pytest.mark.parametrize("chunk", CHUNKS)
def test_automatic_preview_errors_see_one_sample_changed_by_one_ulp(chunk):
    # the errors' fingerprint is the sum of the samples' bit patterns (exact): a change far below
    # what a floating-point sum of the signal would register is still refused
    u = _windowed_sine()
    res = invert(G_NMP, 1e-3, u, chunk_size=chunk)
    u[1234] = np.nextafter(u[1234], np.inf)
    with pytest.raises(InversionError, match="input array was modified in place"):
        _ = res.preview_choice.error_bound
