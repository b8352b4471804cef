"""Check builders shared by the per-seed claim modules (bookkeeping rows and small helpers)."""

from __future__ import annotations

import math

import numpy as np

from .framework import Outcome


def rhp(z, scale: float) -> np.ndarray:
    """The zeros ``z`` in the open right half-plane (real part above 1e-6 × ``scale``)."""
    z = np.asarray(z, complex)
    return z[z.real > 1e-6 * scale]


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
