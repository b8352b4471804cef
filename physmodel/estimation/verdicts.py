"""Verdict semantics of the discrepancy workflow (issue 27 item 5): which bounds matter, effects
reduced to a simpler form, a sign flip, and how large a residual misfit is said to be.

* A parameter of the *named* effect at a candidate bound downgrades the name to ``at_bound`` only
  when the bound matters: relaxing it would lower 2·cost by more than the χ²₁ quantile at the
  user's α (linearised: the outward component of the residual along the parameter's Jacobian
  column with the other free columns projected out, :func:`relax_gain`).  Another candidate
  stopped at its bound never downgrades a closing name (it is noted).
* A parameter of a named effect that ends at its own *off* value (a second time constant of
  1e-57 s, a fluid viscosity share at 1) is not "at a bound": the effect is reported in its
  simpler form without it (:func:`reduced_parameters`).
* Data that the baseline matches with its sign reversed (a constant 180° phase offset, magnitude
  matching) are a polarity/sign-convention issue, said as such (:func:`sign_flip`).
* "A small residual misfit remains" only when the final cost is near its χ² expectation
  (:func:`residual_sentence`); otherwise the residual is called significant, with cost/expected.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np
from scipy.stats import chi2

from ..data.sweep import FrequencySweep
from ..effects import LIBRARY
from .records import FreeParameter
from .residuals import standardised_residuals

#: A parameter within this fraction of its candidate range from its off value counts as "off".
OFF_FRACTION = 1e-6


def relax_threshold(alpha: float) -> float:
    """LR (2·Δcost) above which relaxing one bound would change the fit: χ²₁ quantile at 1 − α."""
    return float(chi2.ppf(1.0 - alpha, 1))


def relax_gain(pm: Callable, values: Mapping[str, float], free: Sequence[FreeParameter], names: Sequence[str],
               data: FrequencySweep, s_ln, s_ph) -> dict:
    """Linearised LR gained by relaxing the bound each parameter of ``names`` sits at.

    ``values``: the fit; ``free``: its free parameters (the Jacobian columns, by one-sided finite
    differences pointing *into* the bounds, so nothing is evaluated outside them).  For parameter k
    at its lower (upper) bound the gain is (J_k⊥ᵀ r)²/‖J_k⊥‖² when the unconstrained step along
    J_k⊥ (J_k with the other columns projected out) points below (above) the bound, else 0.
    Returns ``{name: gain}``."""
    names = [n for n in names if any(fp.name == n for fp in free)]
    if not names:
        return {}
    base = dict(values)
    trial, steps = [base], []
    for fp in free:
        v = base[fp.name]
        span = fp.upper - fp.lower
        h = (1e-6 * abs(v) if (fp.scale == "log" and v != 0) else 1e-6 * span) or 1e-12
        if v + h > fp.upper:           # step into the range
            h = -h
        steps.append(h)
        trial.append({**base, fp.name: v + h})
    G = np.asarray(pm(trial))
    r0 = standardised_residuals(G[0], data, s_ln, s_ph)
    J = np.column_stack([(standardised_residuals(G[i + 1], data, s_ln, s_ph) - r0) / steps[i]
                         for i in range(len(free))])
    out = {}
    idx = {fp.name: i for i, fp in enumerate(free)}
    for n in names:
        k = idx[n]
        fp = free[k]
        others = np.delete(J, k, axis=1)
        col = J[:, k]
        if others.size:
            q, _ = np.linalg.qr(others)
            col = col - q @ (q.T @ col)
        nn = float(col @ col)
        if nn <= 0 or not math.isfinite(nn):
            out[n] = 0.0
            continue
        step = -float(col @ r0) / nn          # the unconstrained Gauss-Newton step along the column
        v = values[n]
        at_lower = abs(v - fp.lower) <= abs(v - fp.upper)
        outward = step < 0 if at_lower else step > 0
        out[n] = float((col @ r0) ** 2 / nn) if outward else 0.0
    return out


def reduced_parameters(effects: Sequence[str], bounds: Sequence[Mapping], values: Mapping[str, float],
                       cpars: Mapping[str, Sequence]) -> list:
    """Parameters of ``effects`` (each with more than one parameter) that ended at a bound equal to
    their off value (``bounds``: :func:`~physmodel.estimation.priors.bound_audit` entries, status
    "at") while the effect itself stays on: ``[{name, effect, parameter, value, off, unit, doc}]``."""
    out = []
    for a in bounds:
        if a["status"] != "at" or "." not in a["name"]:
            continue
        c, pn = a["name"].split(".", 1)
        pars = {p.name: p for p in cpars.get(c, ())}
        if c not in effects or len(pars) < 2 or pn not in pars:
            continue
        p, e = pars[pn], LIBRARY[c]
        if a["bound"] != p.off or e.switch == pn:
            continue
        rest = {q: values.get(f"{c}.{q}", pars[q].off) for q in pars}
        if e.is_off(rest) or all(abs(rest[q] - pars[q].off) <= OFF_FRACTION * (pars[q].upper - pars[q].lower)
                                 for q in pars if q != pn):
            continue
        out.append({"name": a["name"], "effect": c, "parameter": pn, "value": float(a["value"]), "off": float(p.off),
                    "unit": p.unit, "doc": p.doc})
    return out


def reduced_sentence(reduced: Sequence[Mapping]) -> str:
    """'amplifier_bandwidth in its simpler form: second_time_constant = 1e-57 s is its off value 0 (…)'."""
    if not reduced:
        return ""
    return " " + "; ".join(
        f"{x['effect']} in its simpler form: {x['parameter']} ({x['doc'] or x['parameter']}) ends at its off value "
        f"{x['off']:g} ({x['value']:.3g} {x['unit']}), so the data need the effect without it, not a wider bound"
        for x in reduced) + "."


def sign_flip(G0: np.ndarray, data: FrequencySweep, s_ln, s_ph) -> dict:
    """How the data compare with the baseline prediction ``G0`` and with −G0: the weighted costs,
    the mean phase offset of data/G0 [deg, wrapped to (−180, 180]] and the RMS magnitude residual
    [dB]."""
    r_p = standardised_residuals(G0, data, s_ln, s_ph)
    r_m = standardised_residuals(-np.asarray(G0), data, s_ln, s_ph)
    q = data.response / np.asarray(G0)
    ph = np.angle(np.mean(q / np.abs(q)), deg=True)          # circular mean of the phase offset
    return {"cost": float(0.5 * r_p @ r_p), "cost_flipped": float(0.5 * r_m @ r_m), "phase_offset_deg": float(ph),
            "magnitude_rms_db": float(np.sqrt(np.mean((20 * np.log10(np.abs(q))) ** 2)))}


def residual_sentence(cost: float, expected: float, threshold: float, baseline_excess: float, where: str = "") -> str:
    """What is said of the misfit a named model leaves (``cost``: its weighted data cost, ``expected``
    its χ² expectation, ``threshold`` the gap threshold on 2·cost for it, ``baseline_excess`` the
    baseline's 2·cost above its own threshold).  '' within the threshold; "a small residual misfit"
    when 2·cost exceeds the threshold by no more than the threshold exceeds the expectation (the
    cost is near its expectation); otherwise the residual is significant, with cost/expected.
    ``where``: the quantity of a joint record whose block these are (its gap test is per quantity,
    :mod:`~physmodel.estimation.gap`); the sentence then names it."""
    two = 2.0 * cost
    if two <= threshold:
        return ""
    ratio = cost / expected if expected > 0 else float("inf")
    if where:
        where_share = (f"{100.0 * (two - threshold) / baseline_excess:.2g} % of the baseline's excess over its gap "
                       "threshold" if baseline_excess > 0 else "the baseline had no significant gap there")
        if two - threshold <= max(threshold - 2.0 * expected, 0.0):
            return (f" A small residual misfit remains in {where} (weighted cost {ratio:.3g}× its expectation; "
                    f"{where_share}): the data's own law for this effect differs slightly from the library's "
                    "parametrisation.")
        return (f" The residual misfit in {where} is significant: its weighted cost is {ratio:.3g}× its expectation "
                f"({cost:.4g} vs {expected:.4g}; {where_share}): the data's law differs from the library's "
                "parametrisation or something else is missing.")
    share = 100.0 * (two - threshold) / max(baseline_excess, 1e-300)
    if two - threshold <= max(threshold - 2.0 * expected, 0.0):
        return (f" A small residual misfit remains (weighted cost {ratio:.3g}× its expectation; {share:.2g} % of "
                "the baseline's excess over the gap threshold): the data's own law for this effect differs "
                "slightly from the library's parametrisation.")
    return (f" The residual misfit is significant: the weighted cost is {ratio:.3g}× its expectation "
            f"({cost:.4g} vs {expected:.4g}; {share:.2g} % of the baseline's excess over the gap threshold "
            "remains): the named effect explains most of the gap, but the data's law differs from the "
            "library's parametrisation or something else is missing.")


__all__ = ["relax_gain", "relax_threshold", "reduced_parameters", "reduced_sentence", "sign_flip",
           "residual_sentence", "OFF_FRACTION"]
