"""Plausible ranges of the IPMC model's parameters, with their sources.

A *plausible range* is where a parameter of a Nafion-based IPMC strip described by the Chen–Tan
model can be expected to lie — wider than any one strip's uncertainty, narrower than the fit
bounds.  The discrepancy workflow (:func:`physmodel.estimation.discrepancy.diagnose`) holds the
baseline's free parameters to these ranges with a soft penalty
(:mod:`physmodel.estimation.priors`) and reports any fitted value outside them: a baseline that
fits only by leaving its plausible range is itself evidence of a missing effect.

The ranges are deliberately broad (about an order of magnitude around what the seed papers fit,
see ``source``); a user who knows better passes their own :class:`PlausibleRange` records
(``diagnose(plausible={...})``, or ``[plausible]`` in the experiment TOML).  Lumped fit constants
with no independent physical scale (α0, a0) have no range.  ``omega_n`` [rad/s] gets its range
from the modulus and density ranges and the strip's own geometry
(:func:`plausible_ranges`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from .errors import ParameterError
from .params import IPMCParameters

_SEEDS = ("fitted values of the seed papers as shipped in physmodel.parameter_sets (seed000_sensor, "
          "seed002_table2/3)")


@dataclass(frozen=True)
class PlausibleRange:
    """``lower`` ≤ value ≤ ``upper`` in the field's SI unit, with the ``source`` of the range."""

    name: str
    lower: float
    upper: float
    unit: str
    source: str

    def __post_init__(self):
        if not (math.isfinite(self.lower) and math.isfinite(self.upper) and 0 < self.lower < self.upper):
            raise ParameterError(f"plausible range of {self.name}: need 0 < lower < upper (finite), got "
                                 f"[{self.lower!r}, {self.upper!r}]")

    def contains(self, value: float) -> bool:
        return self.lower <= abs(value) <= self.upper

    def decades_outside(self, value: float) -> float:
        """How far |value| lies outside the range [decades] (0 inside)."""
        v = abs(float(value))
        if v <= 0:
            return math.inf
        return max(0.0, math.log10(self.lower / v), math.log10(v / self.upper))

    def describe(self) -> str:
        return f"[{self.lower:.3g}, {self.upper:.3g}] {self.unit} ({self.source})"


#: Default plausible ranges per IPMCParameters field (values at T_ref).
DEFAULT_RANGES: dict[str, PlausibleRange] = {r.name: r for r in (
    PlausibleRange("d", 1e-13, 1e-9, "m^2/s",
                   "cation diffusivity in hydrated Nafion is 1e-11-1e-9 m²/s (water self-diffusion ~1e-9); "
                   "Chen-Tan fits range 2e-13 (seed 000) to 3.5e-11 (seed 002); " + _SEEDS),
    PlausibleRange("C_minus", 500.0, 2500.0, "mol/m^3",
                   "fixed-anion concentration of Nafion: EW 1100 g/mol at 1.6-2 g/cm³ hydrated/dry gives "
                   "~1000-1800 mol/m³; seeds 942-1091"),
    PlausibleRange("kappa_e", 1e-7, 1e-4, "F/m",
                   "effective dielectric permittivity of the Chen-Tan model (includes the electrode "
                   "interface area): seeds fit 4.5e-7-1.3e-6; about one decade below, two above"),
    PlausibleRange("E", 3e7, 2e9, "Pa",
                   "Young's modulus of hydrated Nafion-based IPMC strips, 50 MPa-1 GPa (seeds 154-421 MPa)"),
    PlausibleRange("rho", 1000.0, 60000.0, "kg/m^3",
                   "effective (modal) density: Nafion ~2000 kg/m³ with Pt layers, plus the hydrodynamic added "
                   "mass π ρ_f W²/4 per length in water (Sader 1998), ≈ 6× the strip's own mass for seed 002 "
                   "(W = 4 mm, 2h = 0.25 mm), whose fitted ωn implies ≈ 3.4e4 kg/m³"),
    PlausibleRange("xi", 0.01, 1.0, "1",
                   "first-mode damping ratio of strips in air or water (seeds 0.1-0.18)"),
    PlausibleRange("r1_sheet", 0.1, 5e3, "Ohm",
                   "electrode sheet resistance: fresh Pt a few Ω/sq, cracked/dried up to 10³ Ω "
                   "(Shahinpoor & Kim 2000, Smart Mater. Struct. 9:543); seeds 10-64 Ω"),
    PlausibleRange("r2_specific", 1e-7, 1e-2, "Ohm m^2",
                   "through-thickness/contact area resistance: Nafion 117 1.6e-5 Ω·m² (Slade et al. 2002, "
                   "J. Electrochem. Soc. 149:A1556); seeds ~1e-5"),
    PlausibleRange("Rp_specific", 1e-3, 1e4, "Ohm m^2",
                   "leakage area resistance of the polymer (seeds 0.37-0.5 Ω·m²), a few decades either way"),
)}


def _omega_range(p: IPMCParameters) -> PlausibleRange:
    """ωn = (λ1/L)² sqrt(E (2h)²/(12 ρ)) over the E and ρ ranges, for this strip's L and h."""
    lam1 = 1.8751040687119611
    f = lambda E, rho: (lam1 / p.L) ** 2 * math.sqrt(E * p.h**2 / (3.0 * rho))  # noqa: E731
    E, rho = DEFAULT_RANGES["E"], DEFAULT_RANGES["rho"]
    return PlausibleRange("omega_n", f(E.lower, rho.upper), f(E.upper, rho.lower), "rad/s",
                          f"first clamped-free mode of this strip (L = {p.L:.3g} m, 2h = {2 * p.h:.3g} m) over the "
                          f"E and rho ranges")


def plausible_ranges(params: IPMCParameters, overrides: Mapping[str, PlausibleRange | tuple] | None = None
                     ) -> dict[str, PlausibleRange]:
    """Plausible ranges for the fields of ``params`` (and ``omega_n``): the defaults, replaced by
    ``overrides`` (``{name: PlausibleRange}`` or ``{name: (lower, upper)}``, user-stated)."""
    out = dict(DEFAULT_RANGES)
    out["omega_n"] = _omega_range(params)
    for k, v in (overrides or {}).items():
        if isinstance(v, PlausibleRange):
            out[k] = v
        else:
            try:
                lo, hi = (float(x) for x in v)
            except (TypeError, ValueError):
                raise ParameterError(f"plausible range of {k!r} must be (lower, upper), got {v!r}") from None
            unit = out[k].unit if k in out else ""
            out[k] = PlausibleRange(k, lo, hi, unit, "stated by the user")
    return out


#: Physical limits: values outside these are no IPMC strip at all (and break the numerics), unlike the
#: plausible ranges above, which a fit may leave.  Geometry [m] from the smallest micro-fabricated
#: strips (tens of µm) to the longest cast actuators (tens of cm), with margin; material, electrode
#: and mechanical fields three decades beyond their plausible range either way; T_ref [K] the
#: liquid-water window of hydrated Nafion with margin.
PHYSICAL_LIMITS: dict[str, tuple[float, float, str]] = {
    "L": (1e-5, 10.0, "m"), "W": (1e-6, 1.0, "m"), "h": (1e-7, 1e-2, "m"), "T_ref": (150.0, 600.0, "K"),
    **{k: (r.lower * 1e-3, r.upper * 1e3, r.unit) for k, r in DEFAULT_RANGES.items() if k != "xi"},
    "xi": (1e-5, 100.0, "1"),
}


def check_physical(params: IPMCParameters) -> None:
    """Raise :class:`ParameterError` naming the first field of ``params`` outside
    :data:`PHYSICAL_LIMITS` (zero stays allowed where the field allows it, e.g. ``r1_sheet = 0``,
    and an infinite ``Rp_specific`` means no leakage)."""
    for name, (lo, hi, unit) in PHYSICAL_LIMITS.items():
        v = getattr(params, name, None)
        if v is None:
            continue
        v = abs(float(v))
        if v == 0.0 or (name == "Rp_specific" and math.isinf(v)):
            continue
        if not lo <= v <= hi:
            raise ParameterError(f"{name} = {float(getattr(params, name)):g} {unit} is outside any physical range for an "
                                 f"IPMC strip [{lo:g}, {hi:g}] {unit}" + (" (SI units: metres)" if unit == "m" else ""))


__all__ = ["PlausibleRange", "DEFAULT_RANGES", "plausible_ranges", "PHYSICAL_LIMITS", "check_physical"]
