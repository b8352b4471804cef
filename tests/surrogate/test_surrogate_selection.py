"""Order selection on stand-in physics sweeps, and invariants of the parametrisation."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from surrogate_standin import physics_sweep

from surrogate import RationalModel, Scaling, Structure, order_selection

# seed 001's sample (45 mm x 11 mm x 0.3 mm), first mode scaled from seed 002 by h/L²,
# low electrode resistance; seed 001's protocol: 30 log-spaced lines on 0.1-9 Hz
SEED001_SAMPLE = dict(L=45e-3, h=0.15e-3, W=11e-3, wn=75.4 * (0.15 / 0.125) * (15 / 45) ** 2, r1=2.0)


def test_order_selection_reproduces_the_actuator_finding():
    f, t, h, _, sm, sp = physics_sweep([19.0, 55.0], np.geomspace(0.1, 9, 30), magnitude_std_db=0.3,
                                       phase_std_deg=2.0, params=SEED001_SAMPLE)
    rep = order_selection(f, t, h, [(2, 2), (3, 3), (4, 4)], sm, sp)
    e2, e3, e4 = (rep.row(k, k).worst_relative_rms_error for k in (2, 3, 4))
    assert all(all(r.converged) and all(r.stable) for r in rep.rows)
    assert e2 > 3 * e3                       # second order clearly worse at every temperature
    assert e4 > 0.8 * e3                     # fourth order adds little
    assert rep.row(3, 3).min_fit_percent > 90
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
