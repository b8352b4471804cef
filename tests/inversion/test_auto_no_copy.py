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

from inversion import choose_preview, invert, split_inverse
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
def test_choose_preview_reads_the_callers_array_as_an_untouched_copy(norm):
    split = split_inverse(MODELS["seed000-sensor"])
    u = _signal(6000, 1e-3, 22)
    before = u.tobytes()
    ref = choose_preview(split, 1e-3, u.copy(), norm=norm)
    got = choose_preview(split, 1e-3, u, norm=norm)
    fields = ("samples", "relative_error", "max_error", "error_bound", "tail_bound", "reference_bound")
    assert [getattr(got, f) for f in fields] == [getattr(ref, f) for f in fields]
    assert u.tobytes() == before
