"""``preview="auto"`` keeps no copy of the signal (issue 29): what it computes later from the
caller's array is what inverting a private copy gives, bit for bit, and the caller's array is never
written.

Oracle: the same inversion of an explicit copy of the signal that nothing touches (the copy-then-
invert path ``preview="auto"`` used to take inside), read in full; and the bytes of the caller's
array before the inversion.  Every path of the automatic preview: the ``"linf"`` choice whole-record
and chunked, the chunked ``"l2"`` choice (lazy errors) and the whole-record one (eager), at 1 and
20 kHz, on a nonminimum-phase sensor, a toy actuator and a minimum-phase model (nothing anticausal).
"""

import numpy as np
import pytest

from inversion import InversionError, choose_preview, invert, split_inverse
from inversion.examples import seed000_sensor_35c, toy_actuator

MODELS = {
    "seed000-sensor": seed000_sensor_35c("coefficients"),
    "toy-actuator": toy_actuator(),
    "minimum-phase": (np.poly([-50.0, -500.0]), np.poly([-10.0, -100.0])),
}


def _signal(n, dt, seed):
    t = np.arange(n) * dt
    rng = np.random.default_rng(seed)
    return (np.sin(2 * np.pi * 20 * t) + 0.1 * rng.standard_normal(n)) * np.hanning(n)


def _everything(res, order):
    """Every value a caller can read, in ``order`` (errors first, or parts first)."""
    got = {"output": res.output.copy(), "N": res.preview_samples}
    for what in order:
        if what == "errors":
            c = res.preview_choice
            got["errors"] = (c.relative_error, c.max_error, c.error_bound, c.tail_bound,
                             c.reference_bound, res.truncation_error, res.truncation_bound)
        else:
            got["parts"] = (res.stable_part.copy(), res.unstable_part.copy())
    got["disc"] = res.discretisation_error_estimate
    return got


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("fs", [1e3, 20e3])
@pytest.mark.parametrize("norm, chunk", [("linf", None), ("linf", 700), ("l2", 700), ("l2", None)])
@pytest.mark.parametrize("order", [("errors", "parts"), ("parts", "errors")])
def test_reading_from_the_callers_array_gives_the_bits_of_an_untouched_copy(model, fs, norm, chunk, order):
    dt = 1.0 / fs
    u = _signal(6000, dt, 21)
    before = u.tobytes()
    G = MODELS[model]
    kw = dict(preview="auto", preview_norm=norm, chunk_size=chunk)
    ref = _everything(invert(G, dt, u.copy(), **kw), order)
    res = invert(G, dt, u, **kw)
    assert res.input is u
    got = _everything(res, order)
    assert u.tobytes() == before                      # neither the inversion nor a read wrote into it
    assert got["N"] == ref["N"]
    np.testing.assert_array_equal(got["output"], ref["output"])
    assert got["errors"] == ref["errors"]
    for a, b in zip(got["parts"], ref["parts"], strict=True):
        np.testing.assert_array_equal(a, b)
    assert got["disc"] == ref["disc"]
    if model != "minimum-phase":                      # the case is not empty: a preview and its error
        assert got["N"] > 0 and got["errors"][1] > 0


@pytest.mark.parametrize("norm", ["linf", "l2"])
def test_choose_preview_reads_the_callers_array_as_an_untouched_copy_and_refuses_it_changed(norm):
    split = split_inverse(MODELS["seed000-sensor"])
    u = _signal(6000, 1e-3, 22)
    before = u.tobytes()
    ref = choose_preview(split, 1e-3, u.copy(), norm=norm)
    got = choose_preview(split, 1e-3, u, norm=norm)
    fields = ("samples", "relative_error", "max_error", "error_bound", "tail_bound", "reference_bound")
    assert [getattr(got, f) for f in fields] == [getattr(ref, f) for f in fields]
    assert u.tobytes() == before
    # "linf": the errors are read from the caller's array (no copy) when first read: changed before,
    # refused; whole-record "l2" computes them with the choice (kept whatever happens to the array)
    late = choose_preview(split, 1e-3, u, norm=norm)
    u[3000] = np.nextafter(u[3000], np.inf)
    if norm == "linf":
        with pytest.raises(InversionError, match="modified in place"):
            late.max_error
    else:
        assert late.max_error == ref.max_error


# Changes of the whole record that the sum of the bit patterns alone did not see (review of the
# no-copy change): a power-of-two scaling of 2**13 samples moves every pattern by a multiple of 2**52,
# whose sum is 0 modulo 2**64; an exchange or a shift moves no sum at all.  The extremes see them.
@pytest.mark.parametrize("change", ["times 2", "times 0.5", "roll", "reverse", "swap two"])
@pytest.mark.parametrize("preview", ["auto", 0.05])
def test_a_changed_record_is_refused_for_every_pattern_of_change(change, preview):
    n = 8192
    t = np.arange(n) * 1e-3
    u = np.sin(2 * np.pi * 3 * t + 0.1) + 0.01 * np.random.default_rng(5).standard_normal(n)
    assert np.all(u != 0.0)             # no zero sample, which a scaling leaves as it is
    res = invert(MODELS["seed000-sensor"], 1e-3, u, preview=preview, chunk_size=1000)
    if change == "times 2":
        u *= 2.0
    elif change == "times 0.5":
        u *= 0.5
    elif change == "roll":
        u[:] = np.roll(u.copy(), 1500)
    elif change == "reverse":
        u[:] = u[::-1].copy()
    else:                               # an exchange involving the record's maximum
        k = int(np.argmax(u))
        u[[k, 5000]] = u[[5000, k]]
    if preview == "auto":
        with pytest.raises(InversionError, match="modified in place"):
            res.preview_choice.max_error
        with pytest.raises(InversionError, match="modified in place"):
            res.stable_part
    elif change in ("times 2", "times 0.5", "roll"):    # a given preview's parts: the output's sum
        with pytest.raises(InversionError, match="modified in place"):
            res.stable_part


@pytest.mark.parametrize("preview", ["auto", 0.5])
def test_an_output_whose_sum_overflows_still_refuses_a_changed_input(preview):
    # every output sample finite, their sum not (one-signed, ~1e306): a non-finite sum proves nothing,
    # so the parts are checked by the signal's fingerprint (before: inf == inf let any input through)
    G = ([1.0, -2.0, 5.0], [1.0, 3.0, 4.0])
    n = 4000
    u = np.abs(np.sin(2 * np.pi * 3 * np.arange(n) * 1e-3) * np.hanning(n)) * 1e306
    ref = invert(G, 1e-3, u.copy(), preview=preview)
    res = invert(G, 1e-3, u, preview=preview)
    assert np.isfinite(res.output).all() and not np.isfinite(res.output_sum)
    np.testing.assert_array_equal(invert(G, 1e-3, u, preview=preview).stable_part, ref.stable_part)
    u[1000:3000] *= 0.5
    with pytest.raises(InversionError, match="modified in place"):
        res.stable_part
