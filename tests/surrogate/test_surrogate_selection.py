"""Order selection on stand-in physics sweeps, and invariants of the parametrisation.

The stand-in (surrogate_standin.py) is the seed 002 Chen-Tan model with Table 3's values; here it
gets seed 001's sample geometry and protocol (45 mm x 11 mm x 0.3 mm, first mode scaled from
seed 002 by h/L², 30 log-spaced lines on 0.1-9 Hz, 0.3 dB / 2° noise) and otherwise Table 3 as
printed (r1' = 56.44 Ω, not a value chosen to make a claim pass).  Seed 001's order claims
(Dong and Tan 2012, Sec. 2.3): "second order ... failed to provide a good fit" (reproduced) and
"a fourth-order system provided little improvement over a third-order system" (not reproduced:
measured 4/4 worst error 0.049 against 3/3 0.154; the stand-in's slow charge pole is what a
fourth order captures).  With r1' = 2 Ω and this noise the 4/4 gain hid under the noise floor
(0.044 vs 0.045) - that choice was what made the claim 'pass' before.
"""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from surrogate_standin import physics_sweep

from surrogate import RationalModel, Scaling, Structure, order_selection

SEED001_SAMPLE = dict(L=45e-3, h=0.15e-3, W=11e-3, wn=75.4 * (0.15 / 0.125) * (15 / 45) ** 2)


def test_order_selection_on_the_seed001_protocol():
    f, t, h, _, sm, sp = physics_sweep([19.0, 55.0], np.geomspace(0.1, 9, 30), magnitude_std_db=0.3,
                                       phase_std_deg=2.0, params=SEED001_SAMPLE)
    rep = order_selection(f, t, h, [(2, 2), (3, 3), (4, 4)], sm, sp)
    e2, e3, e4 = (rep.row(k, k).worst_relative_rms_error for k in (2, 3, 4))
    assert all(all(r.converged) and all(r.stable) for r in rep.rows)
    assert e2 > 2 * e3                       # 'second order clearly worse' (read as at least twice the error)
    # 'fourth order adds little' is NOT reproduced: 4/4 more than halves the 3/3 error
    assert e4 < 0.5 * e3, "fourth order now adds little: update the docstring and ipmc validate"
    md = rep.to_markdown()
    assert md.count("\n") == 4 and "| 3 | 3 | 7 |" in md


@settings(max_examples=40, deadline=None)
@given(
    coeffs=st.lists(st.floats(-2, 2), min_size=3 * 6, max_size=3 * 6),
    temperature=st.floats(0.0, 80.0),
)
def test_zpk_poles_are_stable_for_any_parameters_and_temperature(coeffs, temperature):
    model = RationalModel(Structure("zpk", 2, 3, 2), np.array(coeffs), Scaling(10.0, 1.0, 40.0, 20.0),
                          (0.0, 80.0))
    poles = model.poles(temperature)
    assert poles.size == 3 and np.all(poles.real < 0)
    num, den = model.coefficients(temperature)
    scale = np.max(np.abs(poles))
    roots = np.roots(den)
    assert max(np.min(np.abs(roots - p)) for p in poles) <= 1e-6 * scale
