"""Statistics of the discrepancy workflow: residual signatures of candidate effects with the
baseline Jacobian projected out, the constrained likelihood-ratio statistic of the linearised null,
localisation of misfits (band × temperature × magnitude/phase) and the gap test."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from itertools import combinations

import numpy as np

from ..data.sweep import FrequencySweep
from ..effects import LIBRARY, declared_confusable
from .records import FreeParameter
from .residuals import noise_std, standardised_residuals


def z_jacobian(predict_many, values: dict, params: Sequence[FreeParameter], r0, data, s_ln, s_ph, step=1e-4):
    """Forward-difference Jacobian of the standardised residuals in the scaled z space."""
    pts, steps = [], []
    for fp in params:
        z = float(fp.to_z(values[fp.name]))
        lo, hi = fp.z_bounds
        h = step if z + step <= hi else -step
        v = dict(values)
        v[fp.name] = float(fp.from_z(z + h))
        pts.append(v)
        steps.append(h)
    G = predict_many(pts)
    R = standardised_residuals(G, data, s_ln, s_ph)
    return ((R - r0[None, :]) / np.array(steps)[:, None]).T


def effect_signature(predict_many, values: dict, effect: str, r0, data, s_ln, s_ph, params=None, h=1e-3):
    """Columns d r/d δ at "off" for each effect parameter, δ in units of (typical − off);
    and which are one-sided (off at a bound).  ``params``: the effect's parameters with their
    candidate bounds (default: the library's).  ``h``: the step in δ (1: the secant to the typical
    size, for effects whose first-order signature vanishes at off, e.g. a resonance (1 + 2ζτs)/
    (1 + 2ζτs + τ²s²) whose derivative in τ is 0 at τ = 0)."""
    pts, steps, one_sided = [], [], []
    for p in (params if params is not None else LIBRARY[effect].parameters):
        span = p.typical - p.off
        v = dict(values)
        v[f"{effect}.{p.name}"] = p.off + h * span
        pts.append(v)
        steps.append(h)
        one_sided.append(p.off in (p.lower, p.upper))
    G = predict_many(pts)
    R = standardised_residuals(G, data, s_ln, s_ph)
    return ((R - r0[None, :]) / np.array(steps)[:, None]).T, np.array(one_sided)


def orth(A):
    """An orthonormal basis of the columns of ``A`` (QR; columns that add nothing above 1e-10 of the
    largest dropped); ``A`` itself when it has no column."""
    if A.shape[1] == 0:
        return A
    Q, R = np.linalg.qr(A)
    keep = np.abs(np.diag(R)) > 1e-10 * max(1.0, np.abs(np.diag(R)).max())
    return Q[:, keep]


def project_out(Q, A):
    """The columns of ``A`` with the span of the orthonormal ``Q`` (:func:`orth`) removed."""
    return A - Q @ (Q.T @ A) if Q.shape[1] else A


def localise(data: FrequencySweep, r: np.ndarray, alpha: float, n_bands: int = 4) -> list:
    """Standardised residuals by band × temperature × part, flagged at Bonferroni level α.

    A joint record (:class:`~physmodel.estimation.joint.StackedSweep`: ``metadata["quantities"]``
    and ``["block_sizes"]``) is localised per quantity — each block's own bands, every row naming
    its ``"quantity"`` — with the Bonferroni count over all blocks' cells: a gap in Z's lines is
    said as Z's, not pooled into bands shared with M's lines."""
    N = data.frequency_hz.size
    s_ln, s_ph, _ = noise_std(data)
    meta = data.metadata or {}
    qs, sizes = meta.get("quantities"), meta.get("block_sizes")
    if not qs or not sizes or len(qs) != len(sizes) or len(qs) < 2 or sum(int(n) for n in sizes) != N:
        return _localise_lines(data.frequency_hz, data.temperature_c, data.temperatures(), r[:N], r[N:], s_ln, s_ph,
                               alpha, n_bands, None, n_bands * data.temperatures().size * 2)
    ends = np.cumsum([0] + [int(n) for n in sizes])
    blocks = [slice(int(a), int(b)) for a, b in zip(ends[:-1], ends[1:])]
    temps = [np.unique(data.temperature_c[b]) for b in blocks]
    cells = sum(n_bands * t.size * 2 for t in temps)
    rows: list = []
    for q, b, t in zip(qs, blocks, temps):
        rows += _localise_lines(data.frequency_hz[b], data.temperature_c[b], t, r[:N][b], r[N:][b], s_ln[b], s_ph[b],
                                alpha, n_bands, str(q), cells)
    return rows


def _localise_lines(freq, temp_c, temps, r_mag, r_ph, s_ln, s_ph, alpha: float, n_bands: int, quantity, cells: int) -> list:
    """:func:`localise`'s table of one block of lines (frequencies [Hz], temperatures [°C], their
    sorted unique temperatures, the magnitude and phase residuals and σ), ``cells`` the Bonferroni
    count; rows carry ``"quantity"`` when it is not None."""
    from scipy.stats import chi2

    lf = np.log10(freq)
    edges = np.linspace(lf.min(), lf.max() + 1e-12, n_bands + 1)
    band = np.clip(np.searchsorted(edges, lf, side="right") - 1, 0, n_bands - 1)
    parts = (("magnitude", r_mag, s_ln * 20 / math.log(10)), ("phase", r_ph, np.degrees(s_ph)))
    rows = []
    tag = {} if quantity is None else {"quantity": quantity}
    for bi in range(n_bands):
        for pname, rr, scale in parts:
            means = []
            for t in temps:
                m = (band == bi) & (temp_c == t)
                n = int(m.sum())
                if n == 0:
                    continue
                x = rr[m]
                ss = float(np.sum(x * x))
                p = float(chi2.sf(ss, n))
                rows.append({"band_hz": [float(10 ** edges[bi]), float(10 ** edges[bi + 1])],
                             "temperature_c": float(t), "part": pname, "n": n,
                             "rms_std": float(math.sqrt(ss / n)), "mean_std": float(x.mean()),
                             "rms_physical": float(np.sqrt(np.mean((x * scale[m]) ** 2))),
                             "p_value": p, "flagged": bool(p < alpha / cells), **tag})
                means.append((float(t), float(x.mean()), n))
            if len(means) >= 3:
                T = np.array([m[0] for m in means])
                y = np.array([m[1] for m in means])
                w = np.array([m[2] for m in means], float)    # var(mean) = 1/n
                Tm = np.sum(w * T) / w.sum()
                sxx = np.sum(w * (T - Tm) ** 2)
                slope = float(np.sum(w * (T - Tm) * y) / sxx)
                z = slope * math.sqrt(sxx)
                rows.append({"band_hz": [float(10 ** edges[bi]), float(10 ** edges[bi + 1])], "temperature_c": None,
                             "part": pname + " trend with T", "n": int(w.sum()), "rms_std": float("nan"),
                             "mean_std": slope, "rms_physical": float("nan"),
                             "p_value": float(2 * _norm_sf(abs(z))), "flagged": bool(2 * _norm_sf(abs(z)) < alpha / cells),
                             "slope_per_K": slope, "z": float(z), **tag})
    return rows


def _norm_sf(z):
    return 0.5 * math.erfc(z / math.sqrt(2))


def gap_statistics(data: FrequencySweep, r: np.ndarray, n_free: int) -> dict:
    """The gap test's numbers for standardised residuals ``r`` of ``data`` with ``n_free`` fitted
    parameters: cost ½Σr², its expectation N − n_free/2 and spread, their z, and the RMS misfit per
    temperature in dB and degrees."""
    N = data.frequency_hz.size
    s_ln, s_ph, _ = noise_std(data)
    cost = float(0.5 * r @ r)
    exp = N - n_free / 2.0
    temps = data.temperatures()
    db = r[:N] * s_ln * 20 / math.log(10)
    deg = np.degrees(r[N:] * s_ph)
    return {"cost": cost, "expected_cost": exp, "cost_std": math.sqrt(max(exp, 1e-12)),
            "z": (cost - exp) / math.sqrt(max(exp, 1e-12)), "n_free": n_free,
            "temperatures_c": temps.tolist(),
            "rms_db": [float(np.sqrt(np.mean(db[data.temperature_c == t] ** 2))) for t in temps],
            "rms_deg": [float(np.sqrt(np.mean(deg[data.temperature_c == t] ** 2))) for t in temps]}


def separation_hint(a: str, b: str, raw: dict, data: FrequencySweep) -> str:
    """What tells two confusable candidates apart: their magnitude/phase split, their dependence on
    temperature and where in frequency their (unprojected) signatures act."""
    N = data.frequency_hz.size
    temps = data.temperatures()

    def traits(c):
        S = raw[c]
        e2 = np.sum(S * S, axis=1)
        phase = float(e2[N:].sum() / e2.sum())
        per_T = np.array([e2[:N][data.temperature_c == t].sum() + e2[N:][data.temperature_c == t].sum() for t in temps])
        cv = float(per_T.std() / per_T.mean()) if temps.size > 1 else 0.0
        w = e2[:N] + e2[N:]
        fc = float(10 ** (np.sum(w * np.log10(data.frequency_hz)) / w.sum()))
        return phase, cv, fc

    pa, ca, fa = traits(a)
    pb, cb, fb = traits(b)
    hints = []
    if abs(pa - pb) > 0.2:
        hints.append(f"magnitude vs phase ({a} {100 * pa:.0f} % phase, {b} {100 * pb:.0f} %)")
    if abs(ca - cb) > 0.2:
        hints.append(f"temperature dependence (spread over T: {a} {ca:.2f}, {b} {cb:.2f}); add temperatures")
    if abs(math.log10(fa / fb)) > 0.15:
        hints.append(f"frequency (centroids {fa:.3g} Hz vs {fb:.3g} Hz); widen the band")
    if not hints:
        return ("Their first-order signatures coincide on these data; only higher-order terms separate "
                "them: extend the band to where the effects are large.")
    return "Separate by " + "; ".join(hints) + "."


def with_noise(G, e, s_ln, s_ph):
    """``G`` with standardised log-magnitude/phase noise ``e`` (2N,) applied at σ ``s_ln`` [Np], ``s_ph`` [rad]."""
    N = G.size
    return G * np.exp(e[:N] * s_ln + 1j * e[N:] * s_ph)


def vuong_z(r_a, r_b, cost_a: float, cost_b: float) -> float:
    """Vuong's statistic for two non-nested models fitted to the same data, > 0 when ``a`` fits better.

    ``r_a``, ``r_b``: standardised residuals of the data lines (log-magnitude and phase, each an
    independent unit-variance Gaussian term of the log-likelihood); ``cost_*``: the minimised
    costs (½Σr² plus any range penalty, i.e. minus the log-likelihood).
    z = (cost_b − cost_a) / ω with ω² = Σ_i (ℓ_i − ℓ̄)², ℓ_i = (r_b,i² − r_a,i²)/2 the per-residual
    log-likelihood ratio (Vuong 1989, Econometrica 57:307, Theorem 5.1).  Under "equally close to
    the truth" z is asymptotically N(0, 1); for two exactly specified candidates whose fits differ by
    a deterministic signature δ (noiseless λ_ab = ‖δ‖²) z has mean ≈ √λ_ab / 2 and a spread of at
    most 1 (ω also carries the fits' own noise; ≈ 0.8 in tests/estimation/test_vuong.py).  No Akaike/Schwarz
    correction: divided by a small ω it would turn a difference of parameter counts between two
    fits that coincide into a "significant" one.  Identical fits (ω = 0) give 0."""
    ra, rb = np.asarray(r_a, float), np.asarray(r_b, float)
    ell = 0.5 * (rb * rb - ra * ra)
    omega = float(np.sqrt(np.sum((ell - ell.mean()) ** 2)))
    num = cost_b - cost_a
    if omega <= 1e-12 * (1.0 + abs(num)) or not math.isfinite(omega):
        return 0.0
    return float(num / omega)


def vuong_critical(alpha: float) -> float:
    """Two-sided critical value Φ⁻¹(1 − α/2) of :func:`vuong_z` (the better model is chosen by the
    data, so a one-sided test of the chosen one is a two-sided test)."""
    from scipy.stats import norm

    return float(norm.ppf(1.0 - alpha / 2.0))


def vuong_power(lam: float, z_crit: float) -> float:
    """Probability that :func:`vuong_z` exceeds ``z_crit`` when the noiseless fits differ by
    λ = 2·Δcost, in the normal approximation z ~ N(√λ/2, 1): exact at ½ (λ = 4·z_crit²); with the
    smaller real spread it understates the power above ½ and overstates it below.  The normal CDF is
    scipy.special.ndtr, the function scipy.stats.norm.cdf evaluates (the same value, without the
    distribution layer's ~75 µs a call: the next-measurement search asks thousands)."""
    from scipy.special import ndtr

    return float(ndtr(math.sqrt(max(lam, 0.0)) / 2.0 - z_crit))


def _noiseless(data: FrequencySweep, G, s_ln, s_ph) -> FrequencySweep:
    """``data`` with response ``G`` and the same per-line σ."""
    return replace(data, response=G, magnitude_std_db=np.asarray(s_ln) * 20 / math.log(10),
                   phase_std_deg=np.degrees(s_ph))


def vuong_confusability(top: str, sig: Sequence[str], fits: dict, cres: dict, pm, data: FrequencySweep, s_ln, s_ph,
                   z_crit: float, refit) -> dict:
    """Is the best closer ``top`` separated from each other significant candidate?

    ``data``: Vuong's test (:func:`vuong_z`) of ``top`` against it on the measured data — not
    separated when z < ``z_crit``; ``pairs``: the same, two-sided, between the others not separated
    from ``top`` (so an ambiguous set declares which of its pairs the data cannot split).  ``in_band``: each fitted to the other's noiseless prediction at
    its fitted size (``refit(effects, start_values, [None], sim=...)``), λ = 2·data cost; the pair is
    *confusable in this band* when the smaller λ gives Vuong's test less than even odds
    (:func:`vuong_power` < ½, i.e. λ < 4·z_crit²)."""
    pred = {c: pm([fits[c].values])[0] for c in sig}
    r = {c: standardised_residuals(pred[c], data, s_ln, s_ph) for c in sig}
    out: dict = {"top": top, "z_critical": z_crit, "data": [], "in_band": [], "pairs": [],
                 "rule": "Vuong's test of the best closer against each significant candidate, "
                         "two-sided at α; confusable in the band when the noiseless cross-fit λ < 4·z_crit²"}
    for c in sig:
        if c == top:
            continue
        z = vuong_z(r[top], r[c], fits[top].cost, fits[c].cost)
        out["data"].append({"top": top, "other": c, "z": z, "separated": bool(z >= z_crit)})
        lam_ct = 2 * refit([c], fits[c].values, [None], sim=_noiseless(data, pred[top], s_ln, s_ph),
                           identify=False).metadata["data_cost"]
        lam_tc = 2 * refit([top], fits[top].values, [None], sim=_noiseless(data, pred[c], s_ln, s_ph),
                           identify=False).metadata["data_cost"]
        power = vuong_power(min(lam_ct, lam_tc), z_crit)
        out["in_band"].append({"top": top, "other": c, "lambda_other_to_top": lam_ct, "lambda_top_to_other": lam_tc,
                               "power": power, "confusable": bool(power < 0.5)})
    rest = [x["other"] for x in out["data"] if not x["separated"]]
    for a, b in combinations(rest, 2):     # within an ambiguous set: the other pairs, two-sided
        z = vuong_z(r[a], r[b], fits[a].cost, fits[b].cost)
        out["pairs"].append({"top": a, "other": b, "z": z, "separated": bool(abs(z) >= z_crit)})
    return out


def _cosine(Sa, Sb) -> float:
    """Largest canonical correlation between two signature blocks (nan if either is empty)."""
    Qa, Qb = orth(Sa), orth(Sb)
    if Qa.shape[1] == 0 or Qb.shape[1] == 0:
        return float("nan")
    return float(min(np.linalg.svd(Qa.T @ Qb, compute_uv=False).max(), 1.0))


def declare_confusable(confusable: list, separation: dict, confusability: dict, sigs: dict, raw_sigs: dict, data) -> None:
    """Add to ``confusable``/``separation`` (in place) the pairs the data do not separate and those
    confusable in this band (from :func:`vuong_confusability`), each with its reason."""
    declared = {frozenset(x[:2]) for x in confusable}
    rows = [(x, f"not separated by the data (Vuong z = {x['z']:.3g})")
            for x in confusability["data"] + confusability.get("pairs", []) if not x["separated"]]
    rows += [(x, "confusable in this band at the fitted sizes (noiseless cross-fit λ = "
                 f"{min(x['lambda_other_to_top'], x['lambda_top_to_other']):.3g})")
             for x in confusability["in_band"] if x["confusable"]]
    for x, why in rows:
        a, b = x["top"], x["other"]
        key = f"{a}~{b}" if f"{b}~{a}" not in separation else f"{b}~{a}"
        if frozenset((a, b)) not in declared:
            declared.add(frozenset((a, b)))
            confusable.append((a, b, _cosine(sigs[a], sigs[b])))
            separation[key] = separation_hint(a, b, raw_sigs, data)
        separation[key] = separation.get(key, "") + f" Declared: {why}."
        same_physics = declared_confusable(a, b)
        if same_physics and "two forms" not in separation[key]:
            separation[key] += f" The library holds them as one physics in two forms: {same_physics}."


def refit_spread(res, origins: Sequence[str], tol: float = 1.0) -> dict:
    """Multi-start record of a candidate refit ``res`` (one multi-start search, start k from
    ``origins[k]``): the costs, origins, the best's origin, how many reach the best cost within
    ``tol`` (½Δχ²) — a start that stopped early in the basin of one that did (status −2,
    :func:`~physmodel.estimation.lsq.joined_start`) counts as reaching it — the cost spread of the
    starts that ran to their end and each parameter's range over the starts that reach the best."""
    from .lsq import joined_start

    st = res.starts
    ran = [x for x in st if x.status != -2]
    best = min(ran, key=lambda x: x.cost)
    near = [x for x in ran if x.cost <= best.cost + tol]
    at_best = {x.index for x in near}
    for x in st:                 # joined starts follow the start they joined (an earlier one)
        j = joined_start(x)
        if j is not None and j in at_best:
            at_best.add(x.index)
    costs = [float(x.cost) for x in st]
    return {"n_starts": len(st), "costs": costs, "origins": list(origins), "best_origin": origins[best.index],
            "n_at_best": len(at_best), "n_joined": sum(x.status == -2 for x in st),
            "cost_spread": max(float(x.cost) for x in ran) - float(best.cost),
            "ranges": {n: [float(min(x.final[n] for x in near)), float(max(x.final[n] for x in near))]
                       for n in res.names}}


def pair_members(best: Sequence[str], other: Sequence[str], sigs: dict) -> list:
    """The members in which two pairs differ, matched one to one (by the larger signature cosine
    when both differ)."""
    db, do = [m for m in best if m not in other], [m for m in other if m not in best]
    if len(db) != len(do) or not db:
        return []
    if len(db) == 1:
        return [(db[0], do[0])]
    straight = _cosine(sigs[db[0]], sigs[do[0]]) + _cosine(sigs[db[1]], sigs[do[1]])
    crossed = _cosine(sigs[db[0]], sigs[do[1]]) + _cosine(sigs[db[1]], sigs[do[0]])
    return list(zip(db, do if not crossed > straight else do[::-1]))
