"""Several measured quantities of one strip, diagnosed together (issue 27, item 2; discrepancy.md §"Joint diagnosis").

:func:`~physmodel.estimation.discrepancy.diagnose` takes one
:class:`~physmodel.data.sweep.FrequencySweep` (one measured quantity) or a sequence of them, one per
quantity — an actuator's tip displacement per volt M and its impedance Z, a sensor's current S and
Z.  The lines of every quantity are stacked into one record (:class:`StackedSweep`): the
standardised residuals (:func:`~physmodel.estimation.residuals.standardised_residuals`,
log-magnitude and phase over each line's own σ) are unit-free once each quantity is predicted in its
own sweep's units, so the baseline, every candidate refit, the linearised null and the bootstrap
refits of the diagnosis run unchanged on the stacked lines — one data path (the gap test alone
is per quantity, below).  The predictor
(:meth:`JointData.predictor`) evaluates each quantity at its own sweep's lines with
the model's ``predictor(sweep, quantity)`` and concatenates them; an effect that acts on one
quantity only leaves the other unchanged (the library's ``quantities``), so it is still fitted
jointly.  Where the quantities come from different instruments, ``acts_on`` narrows where an
effect acts (``{"amplifier_bandwidth": ["S"], "time_delay": ["S"]}``: the current amplifier and
the acquisition of S do not carry an impedance analyser's Z): on the other quantities it is held
at its off values.

Noise, per quantity: a sweep that declares per-line standard deviations keeps them; one that does
not gets its own estimate (:func:`estimate_noise`): the RMS of the second differences along
frequency, within each temperature, of the log-magnitude and phase residuals of a provisional joint
baseline (those beyond :data:`TRIM` robust σ — 1.4826 × their median absolute value — left out),
divided by √6 (the variance of x₋ − 2x₀ + x₊ for white noise of variance σ²).  Differencing removes a smooth misfit, so a missing effect is not
absorbed into the noise; the provisional baseline is weighted with the same estimate made on the
data themselves (third differences of ln G, which a smooth response hardly moves), so a noisy
quantity does not dominate it.  Each quantity's σ is one number for magnitude and one for phase.

The gap test is per quantity (:mod:`~physmodel.estimation.gap`): each quantity's block of rows has
its own 2·cost statistic and null quantile at α_gap/K (Bonferroni over the K quantities); the
baseline's gap is significant when some block's is, and a candidate or pair closes it only when it
closes it in every block — pooled over all lines, an effect on M alone was diluted by Z's lines,
and a model could close the pooled gap while leaving M's.  Everything else (fits, LR, null draws)
runs on the stacked lines.

The report (``Diagnosis.per_quantity``) gives each quantity's
lines, noise (declared or estimated) and its cost before and after against its expectation, so a
misfit left in one quantity is visible, and the gap test's thresholds there before and after
(``gap_before``: the baseline's gap significant there; ``gap_left``: not closed there).  With estimated noise that cost is not a test (the
estimate has a relative spread of about 1/√(lines); the same rule as for one quantity, whose
estimated-noise cost is not checked either), so ``misfit`` is then None.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..data.sweep import FrequencySweep
from ..data.units import QUANTITY_UNITS, UNITS
from ..effects import DEFAULT_QUANTITY, get_effect
from ..errors import DataFormatError, IPMCError
from .frf_estimate import NEPER_TO_DB
from .residuals import noise_std, standardised_residuals

#: Robust spread: σ ≈ MAD_SCALE · median |x − median| of Gaussian x; here of differences with median 0.
MAD_SCALE = 1.4826
#: Differences beyond this many robust σ are left out of the (otherwise RMS) estimate: the RMS is
#: about 2.7× as efficient as the MAD for Gaussian noise; 4σ trims 0.006 % of Gaussian differences.
TRIM = 4.0


@dataclass(frozen=True)
class StackedSweep(FrequencySweep):
    """The lines of several quantities of one strip, one block per quantity (in the order of
    ``metadata["quantities"]``, sizes ``metadata["block_sizes"]``).  Units are "1": each block is in
    its own sweep's units; a line's temperature and frequency are its own.  Within a block the
    frequencies at each temperature increase (checked on the sweeps it is stacked from); across
    blocks they repeat, so only that check of :class:`FrequencySweep` is left out."""

    def __post_init__(self):
        T = np.asarray(self.temperature_c, dtype=float).reshape(-1)
        f = np.asarray(self.frequency_hz, dtype=float).reshape(-1)
        H = np.asarray(self.response, dtype=complex).reshape(-1)
        if not (T.size == f.size == H.size) or T.size == 0:
            raise IPMCError(f"a stacked sweep needs one temperature, frequency and response per line; "
                            f"got {T.size}, {f.size}, {H.size}")
        if not (np.all(np.isfinite(T)) and np.all(np.isfinite(f)) and np.all(f > 0) and np.all(np.isfinite(H))
                and np.all(H != 0)):
            raise IPMCError("a stacked sweep's lines must be finite, at positive frequencies, with non-zero responses")
        object.__setattr__(self, "temperature_c", T)
        object.__setattr__(self, "frequency_hz", f)
        object.__setattr__(self, "response", H)
        for name in ("magnitude_std_db", "phase_std_deg"):
            v = getattr(self, name)
            if v is not None:
                v = np.asarray(v, dtype=float).reshape(-1)
                if v.size != T.size or not np.all(np.isfinite(v)) or np.any(v < 0):
                    raise IPMCError(f"{name} must hold one finite value >= 0 per line")
                object.__setattr__(self, name, v)


def quantity_of(sweep: FrequencySweep, kind: str, given: str | None = None, where: str = "data") -> str:
    """The measured quantity of ``sweep`` for a ``kind`` model: ``given``, else the sweep's
    ``metadata["quantity"]``, else the one whose units match (M before H for mm/V); an error naming
    ``where`` when the units fit none or ``given`` does not fit them."""
    qs = [q for k, q in QUANTITY_UNITS if k == kind and q != "G"]
    if given is None:
        meta = (sweep.metadata or {}).get("quantity")
        given = meta if meta in qs else None
    dims = (UNITS[sweep.input_unit][0], UNITS[sweep.output_unit][0])
    fits = [q for q in qs if (UNITS[QUANTITY_UNITS[(kind, q)][1]][0], UNITS[QUANTITY_UNITS[(kind, q)][3]][0]) == dims]
    if given is not None:
        if given not in qs:
            raise IPMCError(f"{where}: quantity {given!r} is not one of the {kind} quantities {qs}")
        if given not in fits:
            raise DataFormatError(f"{where}: {sweep.output_name} [{sweep.output_unit}] per {sweep.input_name} "
                                  f"[{sweep.input_unit}] cannot be the {kind} quantity {given} "
                                  f"(units {QUANTITY_UNITS[(kind, given)]}); its units fit {fits or 'none'}")
        return given
    if not fits:
        raise DataFormatError(f"{where}: {sweep.output_name} [{sweep.output_unit}] per {sweep.input_name} "
                              f"[{sweep.input_unit}] is no {kind} quantity; expected the units of one of "
                              + ", ".join(f"{q} ({QUANTITY_UNITS[(kind, q)][3]}/{QUANTITY_UNITS[(kind, q)][1]})"
                                          for q in qs))
    return DEFAULT_QUANTITY[kind] if DEFAULT_QUANTITY[kind] in fits else fits[0]


@dataclass(frozen=True)
class JointData:
    """Several quantities of one strip, stacked (see the module docstring).

    ``sweeps``: one per quantity, each with the per-line σ used (declared, or estimated and written
    in); ``quantities``: their names; ``noise``: ``"declared"`` or ``"estimated"`` per quantity;
    ``stacked``: the :class:`StackedSweep` of their lines, block by block."""

    sweeps: tuple
    quantities: tuple
    noise: tuple
    stacked: FrequencySweep = field(repr=False)

    @property
    def sizes(self) -> list[int]:
        """Lines per quantity."""
        return [s.frequency_hz.size for s in self.sweeps]

    @property
    def slices(self) -> list[slice]:
        """Each quantity's lines in the stacked record."""
        e = np.cumsum([0] + self.sizes)
        return [slice(int(a), int(b)) for a, b in zip(e[:-1], e[1:])]

    @property
    def label(self) -> str:
        """The quantities joined by "+" (e.g. ``"M+Z"``): the diagnosis's ``quantity``."""
        return "+".join(self.quantities)

    @property
    def any_estimated(self) -> bool:
        """Some quantity's σ is estimated (its sweep declared none)."""
        return "estimated" in self.noise

    def split(self, G) -> list[np.ndarray]:
        """A stacked prediction (…, N) as one array per quantity."""
        G = np.asarray(G)
        return [G[..., s] for s in self.slices]

    def predictor(self, model, acts_on: Mapping[str, Sequence[str]] | None = None) -> Callable:
        """``many(values_list) -> (n_sets, N)``: each quantity at its own sweep's lines, in its units.

        ``acts_on``: ``{effect: quantities}`` narrowing where an effect acts (e.g. a current
        amplifier's pole on S only, when Z is measured by another instrument); on the other
        quantities the effect is held at its off values."""
        parts = []
        for s, q in zip(self.sweeps, self.quantities):
            off = {f"{e}.{k}": v for e, qs in (acts_on or {}).items() if q not in qs for k, v in get_effect(e).off.items()}
            present = {k.split(".", 1)[0] for k in off} & set(getattr(model, "effects", {}) or {})
            parts.append((model.predictor(s, q).many, off, present))

        def many(values_list):
            out = []
            for pm, off, present in parts:
                vals = values_list if not off else [
                    {**v, **{k: o for k, o in off.items() if k in v or k.split(".", 1)[0] in present}} for v in values_list]
                out.append(np.asarray(pm(vals), dtype=complex))
            return np.hstack(out)
        return many

    def with_sigma(self, sigmas: Sequence[tuple[float, float] | None], noise: Sequence[str]) -> JointData:
        """The same lines, quantity k with σ_ln, σ_φ = ``sigmas[k]`` [Np, rad] (None: unchanged)."""
        out = []
        for s, sg in zip(self.sweeps, sigmas):
            if sg is not None:
                n = s.frequency_hz.size
                s = replace(s, magnitude_std_db=np.full(n, sg[0] * NEPER_TO_DB), phase_std_deg=np.full(n, math.degrees(sg[1])))
            out.append(s)
        return _build(tuple(out), self.quantities, tuple(noise))

    def resolve_noise(self, fit_baseline: Callable[[FrequencySweep], np.ndarray]) -> JointData:
        """Per-quantity σ where a sweep declares none: a provisional σ from the data
        (:func:`data_noise`), the joint baseline fitted with it (``fit_baseline(stacked)`` returns its
        stacked prediction), then each quantity's σ from that fit's residuals (:func:`estimate_noise`)."""
        if not self.any_estimated:
            return self
        prov = self.with_sigma([data_noise(s) if n == "estimated" else None
                                for s, n in zip(self.sweeps, self.noise)], self.noise)
        G = prov.split(fit_baseline(prov.stacked))
        return self.with_sigma([estimate_noise(s, g) if n == "estimated" else None
                                for s, g, n in zip(self.sweeps, G, self.noise)], self.noise)

    def per_quantity(self, G_before, G_after, n_free_before: int, n_free_after: int, alpha: float) -> list[dict]:
        """Each quantity's lines, noise and weighted cost before/after against its expectation
        (the fitted parameters shared out by lines), with ``misfit`` when 2·cost after exceeds the
        χ² quantile at α/len(quantities) (None for estimated noise: not a test).  The diagnosis passes
        the model file's goodness-of-fit level (:data:`~physmodel.estimation.residuals.GOF_ALPHA`,
        the level of the pooled "does the model fit" verdict), so one quantity's misfit is judged at
        the same family-wise level as the whole."""
        from scipy.stats import chi2

        N = sum(self.sizes)
        rows = []
        for s, q, nz, gb, ga in zip(self.sweeps, self.quantities, self.noise, self.split(G_before), self.split(G_after)):
            s_ln, s_ph, _ = noise_std(s)
            n = s.frequency_hz.size
            cb = float(0.5 * np.sum(standardised_residuals(gb, s, s_ln, s_ph) ** 2))
            ca = float(0.5 * np.sum(standardised_residuals(ga, s, s_ln, s_ph) ** 2))
            exp_b, exp_a = n - 0.5 * n_free_before * n / N, n - 0.5 * n_free_after * n / N
            dof = max(2 * exp_a, 1.0)
            rows.append({"quantity": q, "lines": int(n), "unit": f"{s.output_unit}/{s.input_unit}", "noise": nz,
                         "sigma_db_median": float(np.median(s_ln) * NEPER_TO_DB),
                         "sigma_deg_median": float(np.degrees(np.median(s_ph))),
                         "cost_before": cb, "expected_before": exp_b, "cost_after": ca, "expected_after": exp_a,
                         "z_after": (ca - exp_a) / math.sqrt(max(exp_a, 1e-12)),
                         "misfit": None if nz == "estimated" else
                         bool(2 * ca > chi2.ppf(1 - alpha / len(self.quantities), dof))})
        return rows


def _build(sweeps: tuple, quantities: tuple, noise: tuple) -> JointData:
    cat = lambda name: np.concatenate([getattr(s, name) for s in sweeps])  # noqa: E731
    sd = [noise_std(s) for s in sweeps]
    stacked = StackedSweep(cat("temperature_c"), cat("frequency_hz"), cat("response"),
                           np.concatenate([x[0] for x in sd]) * NEPER_TO_DB, np.degrees(np.concatenate([x[1] for x in sd])),
                           "+".join(s.input_name for s in sweeps), "1", "+".join(s.output_name for s in sweeps), "1",
                           {"quantities": list(quantities), "block_sizes": [s.frequency_hz.size for s in sweeps],
                            "noise": list(noise), "units": [f"{s.output_unit}/{s.input_unit}" for s in sweeps]})
    return JointData(sweeps, quantities, noise, stacked)


def check_acts_on(acts_on: Mapping | None, kind: str, quantities: Sequence[str]) -> dict:
    """``acts_on`` validated: ``{effect name: tuple of quantities}``, each quantity among ``quantities``
    and applicable to the effect; a ParameterError naming the entry otherwise."""
    from ..errors import ParameterError

    out: dict = {}
    for e, qs in (acts_on or {}).items():
        eff = get_effect(e)
        qs = (qs,) if isinstance(qs, str) else tuple(qs)
        bad = [q for q in qs if q not in quantities or not eff.applies_to(kind, q)]
        if bad or not qs:
            raise ParameterError(f"acts_on[{e!r}] = {list(qs)}: expected some of the quantities diagnosed "
                                 f"{list(quantities)} that the effect acts on ({list(eff.quantities)})")
        out[eff.name] = qs
    return out


def joint_data(data: Sequence[FrequencySweep], kind: str, quantity: str | Sequence[str] | None = None) -> JointData:
    """The :class:`JointData` of a sequence of sweeps, one per quantity (``quantity``: their names in
    order, or None to take each from its sweep's metadata/units, :func:`quantity_of`).  Two sweeps of
    the same quantity are an error (merge them first:
    :func:`~physmodel.estimation.next_measurement.merge_records`)."""
    sweeps = list(data)
    if not sweeps:
        raise IPMCError("data: an empty sequence of sweeps; give one FrequencySweep per measured quantity")
    for i, s in enumerate(sweeps):
        if not isinstance(s, FrequencySweep):
            raise IPMCError(f"data[{i}] must be a FrequencySweep, got {type(s).__name__}")
    if quantity is None or isinstance(quantity, str):
        given = [quantity] * len(sweeps) if (quantity is not None and len(sweeps) == 1) else [None] * len(sweeps)
        if isinstance(quantity, str) and len(sweeps) > 1:
            raise IPMCError(f"quantity={quantity!r} for {len(sweeps)} sweeps: give one quantity per sweep, "
                            "e.g. quantity=('M', 'Z'), or None to take each from its sweep's units")
    else:
        given = list(quantity)
        if len(given) != len(sweeps):
            raise IPMCError(f"quantity={tuple(given)!r} names {len(given)} quantities for {len(sweeps)} sweeps")
    qs = tuple(quantity_of(s, kind, g, f"data[{i}]") for i, (s, g) in enumerate(zip(sweeps, given)))
    dup = sorted({q for q in qs if qs.count(q) > 1})
    if dup:
        raise IPMCError(f"data: several sweeps of quantity {dup} ({list(qs)}); merge the records of one quantity "
                        "into one sweep first (physmodel.estimation.next_measurement.merge_records)")
    noise = tuple("estimated" if noise_std(s)[2] else "declared" for s in sweeps)
    return _build(tuple(sweeps), qs, noise)


def per_quantity_sentence(rows: Sequence[dict], pooled: dict | None = None) -> str:
    """The report's sentence on each quantity's cost after the diagnosis ('' for one quantity);
    ``pooled``: the pooled gap test (:meth:`~physmodel.estimation.gap.GapTest.pooled_row`), named
    when it leaves the gap open."""
    if not rows:
        return ""
    parts = [f"{r['quantity']} ({r['lines']} lines, {r['noise']} noise {r['sigma_db_median']:.3g} dB / "
             f"{r['sigma_deg_median']:.3g}°): weighted cost {r['cost_before']:.4g} → {r['cost_after']:.4g} "
             f"(expected {r['expected_after']:.4g}" + (", not a test with estimated noise)" if r["misfit"] is None else ")")
             for r in rows]
    bad = [r["quantity"] for r in rows if r["misfit"]]
    # the diagnosis's gap test (gap.py): where it leaves the gap open, per quantity and pooled
    gap = [f"in {r['quantity']} (2·cost {2 * r['cost_after']:.4g} > {r['gap_threshold_after_2cost']:.4g})"
           for r in rows if r.get("gap_left")]
    if pooled and pooled.get("gap_left"):
        gap.append(f"{pooled['test']} (2·cost {pooled['two_cost_after']:.4g} > {pooled['threshold_after_2cost']:.4g}"
                   + ("; each quantity alone closes it)" if not gap else ")"))
    return (" Diagnosed jointly over " + ", ".join(r["quantity"] for r in rows) + ": " + "; ".join(parts) + "."
            + (f" A misfit remains in {', '.join(bad)}: its cost is above its χ² band after the diagnosis."
               if bad else "")
            + (" The gap test leaves the gap open " + "; ".join(gap) + "." if gap else ""))


# =============================================================================== noise estimates
def _log_parts(sweep: FrequencySweep, G=None) -> tuple[np.ndarray, np.ndarray]:
    """ln|·| and unwrapped phase (per temperature) of the data, or of data/G."""
    q = sweep.response if G is None else sweep.response / np.asarray(G)
    ph = np.empty(q.size)
    for t in sweep.temperatures():
        idx = np.flatnonzero(sweep.temperature_c == t)
        ph[idx] = np.unwrap(np.angle(q[idx]))
    return np.log(np.abs(q)), ph


def _robust_sigma(sweep: FrequencySweep, x: np.ndarray, order: int) -> float:
    """σ of white noise on ``x`` from the RMS of its ``order``-th differences along frequency within
    each temperature (those beyond :data:`TRIM` robust σ left out; variance of the k-th
    difference: C(2k, k)·σ²)."""
    per_t = [np.diff(x[sweep.temperature_c == t], n=order) for t in sweep.temperatures()]
    d = np.concatenate([v for v in per_t if v.size]) if any(v.size for v in per_t) else np.zeros(0)
    if d.size < 3:
        raise IPMCError(f"cannot estimate the noise of a {sweep.output_name} sweep from {sweep.frequency_hz.size} "
                        f"lines: give at least {order + 3} frequencies per temperature, or declare per-line "
                        "standard deviations (magnitude_std_db, phase_std_deg)")
    c = math.comb(2 * order, order)
    s = MAD_SCALE * float(np.median(np.abs(d))) / math.sqrt(c)          # robust first guess
    keep = np.abs(d) <= TRIM * math.sqrt(c) * s                           # an odd line (a resonance) left out
    s = math.sqrt(float(np.mean(d[keep] ** 2)) / c) if np.count_nonzero(keep) >= 3 else s
    return max(s, 1e-9)


def data_noise(sweep: FrequencySweep) -> tuple[float, float]:
    """Provisional (σ_ln [Np], σ_φ [rad]) of a sweep from its own third differences (no model)."""
    a, p = _log_parts(sweep)
    return _robust_sigma(sweep, a, 3), _robust_sigma(sweep, p, 3)


def estimate_noise(sweep: FrequencySweep, G) -> tuple[float, float]:
    """(σ_ln [Np], σ_φ [rad]) of a sweep from the second differences of its residuals to the
    prediction ``G`` (a smooth misfit hardly moves them)."""
    a, p = _log_parts(sweep, G)
    return _robust_sigma(sweep, a, 2), _robust_sigma(sweep, p, 2)


__all__ = ["check_acts_on", "JointData", "StackedSweep", "joint_data", "quantity_of", "estimate_noise", "data_noise", "MAD_SCALE", "TRIM",
           "per_quantity_sentence"]
