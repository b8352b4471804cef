"""Check builders shared by the per-seed claim modules (bookkeeping rows and small helpers)."""

from __future__ import annotations

import math

import numpy as np

from .claims import Outcome

#: How far beyond the top of the fitted band a zero may lie and still count [× band top]: a zero a
#: decade above the highest fitted frequency changes the in-band response by at most about 6° of
#: phase (atan 0.1) and 0.04 dB of magnitude per zero, so a fit to measured data cannot place it, nor
#: tell which half-plane it is in.  Fixed from that argument, not from the rows it decides.
ZERO_REACH = 10.0
#: A fit misfit below this relative RMS error (5 %, about 0.4 dB) is not visible on a Bode plot of measured
#: data (the bound the seed 000 order row uses too): a fit 'clearly worse' than another must exceed it.
VISIBLE_MISFIT = 0.05


def rhp(z, band_top_rad_s: float) -> np.ndarray:
    """The zeros ``z`` of a fit that are right-half-plane zeros the fitted band constrains.

    A zero counts when it is finite, within :data:`ZERO_REACH` × ``band_top_rad_s`` (the top of the
    fitted band [rad/s]) of the origin, and has a real part above 1e-6 × ``band_top_rad_s``.  A fit of
    higher order than the data need puts its spare zeros far outside the band (numerically infinite
    for a system with fewer zeros than the fit); those are not zeros of the data, whichever
    half-plane the fitter happens to leave them in.
    """
    z = np.asarray(z, complex).ravel()
    top = float(band_top_rad_s)
    keep = np.isfinite(z) & (np.abs(z) <= ZERO_REACH * top) & (z.real > 1e-6 * top)
    return z[keep]


def paper_check(ctx, value):
    return Outcome(f"text file {value}", "names the text the section's numbers were transcribed from", bool(str(value)))


def io_check(kind, quantity, which):
    """The printed unit of the input or output equals the unit our sweeps of ``quantity`` use."""
    def check(ctx, value):
        from physmodel.data.units import QUANTITY_UNITS

        _, i_unit, _, o_unit = QUANTITY_UNITS[(kind, quantity)]
        unit = i_unit if which == "input" else o_unit
        printed_unit = str(value).split("[")[-1].rstrip("]").strip()
        return Outcome(f"{kind} sweeps ({quantity}) use [{unit}]", "same unit as printed", unit == printed_unit)
    return check


def geometry_check(set_name, L_key, W_key, t_key, t_scale):
    """The parameter set's length, width and thickness equal the printed ones."""
    def check(ctx, value):
        p = ctx.parameter_set(set_name)
        ok = (math.isclose(p.L * 1e3, value[L_key], rel_tol=1e-9) and math.isclose(p.W * 1e3, value[W_key], rel_tol=1e-9)
              and math.isclose(2 * p.h * t_scale, value[t_key], rel_tol=1e-9))
        return Outcome(f"{p.name}: L = {p.L*1e3:g} mm, W = {p.W*1e3:g} mm, thickness = {2*p.h*t_scale:g} "
                       f"{'um' if t_scale == 1e6 else 'mm'}", "equal to the printed geometry", ok)
    return check
