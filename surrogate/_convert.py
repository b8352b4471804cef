"""Converting a fitted structure's roots between forms: grouping poles/zeros into real and
complex-pair slots consistently across temperatures, stabilising roots, and re-expressing a model
in another form (coefficients ↔ zpk ↔ sections)."""

from __future__ import annotations

import itertools

import numpy as np

from ._structure import Structure, factor_roots, polynomials, roots, section_polys, slot_values, zero_section_polys


# --------------------------------------------------- grouping roots into factors
def _pairings(reals, n_pairs, single):
    """All ways to split the real roots into n_pairs pairs (+ one single if requested)."""
    idx = list(range(len(reals)))
    singles = idx if single else [None]
    for s in singles:
        rest = [i for i in idx if i != s]

        def matchings(items):
            if not items:
                yield []
                return
            a = items[0]
            for j in range(1, len(items)):
                b = items[j]
                for tail in matchings(items[1:j] + items[j + 1:]):
                    yield [(a, b)] + tail

        for mt in matchings(rest):
            yield mt, s


def group_roots(rts, reference=None):
    """Group the roots of a real polynomial into quadratic factors and (odd degree) one linear.

    Complex roots stay with their conjugates; real roots are paired.  Without ``reference``
    the pairing is canonical (adjacent sorted reals, factors by increasing |root|); with a
    reference grouping of the same size (e.g. from a neighbouring temperature) the pairing
    and order closest to it are chosen, so section identities are tracked continuously.
    Returns ``(quads, single)``: list of 2-root arrays and a 1-root array or None.
    """
    rts = np.asarray(rts, complex)
    n = len(rts)
    is_real = np.abs(rts.imag) <= 1e-9 * np.maximum(1.0, np.abs(rts))     # |Im r| <= 1e-9·max(1, |r|)
    real = rts.real[is_real].tolist()
    upper = list(rts[~is_real & (rts.imag > 0)])
    lower = list(rts[~is_real & (rts.imag < 0)])
    if len(upper) != len(lower):  # numerically broken conjugate symmetry: treat as reals
        real = sorted(r.real for r in rts)
        upper = []
    cquads = [np.array([u, np.conj(u)]) for u in upper]
    n_real_pairs = n // 2 - len(cquads)
    real = sorted(real)
    if reference is None:
        single = None
        rr = list(real)
        if n % 2:
            # the real root farthest from the rest is the linear factor
            single = np.array([complex(rr.pop(int(np.argmax(np.abs(rr)))))])
        rq = [np.array([complex(rr[2 * i]), complex(rr[2 * i + 1])]) for i in range(n_real_pairs)]
        quads = sorted(cquads + rq, key=lambda q: abs(q[0] * q[1]))
        return quads, single
    ref_quads, ref_single = reference

    def dist(a, b):
        a, b = np.asarray(a), np.asarray(b)
        scale = 1.0 + np.abs(b)
        if len(a) == 1:
            return float(abs(a[0] - b[0]) / scale[0])
        d1 = abs(a[0] - b[0]) / scale[0] + abs(a[1] - b[1]) / scale[1]
        d2 = abs(a[1] - b[0]) / scale[0] + abs(a[0] - b[1]) / scale[1]
        return float(min(d1, d2))

    best = None
    for mt, s in _pairings(real, n_real_pairs, n % 2 == 1):
        quads = cquads + [np.array([complex(real[a]), complex(real[b])]) for a, b in mt]
        single = None if s is None else np.array([complex(real[s])])
        base = 0.0 if single is None else dist(single, ref_single)
        for perm in itertools.permutations(range(len(quads))):
            cost = base + sum(dist(quads[p], ref_quads[i]) for i, p in enumerate(perm))
            if best is None or cost < best[0]:
                best = (cost, [quads[p] for p in perm], single)
    return best[1], best[2]


def quad_coefficients(q) -> tuple[float, float]:
    """(c1, c0) of (s − r1)(s − r2) = s² + c1 s + c0."""
    return float(-(q[0] + q[1]).real), float((q[0] * q[1]).real)


def stabilise_roots(rts, floor: float = 1e-3) -> np.ndarray:
    """Reflect right-half-plane roots into the left half plane, keep a small damping floor."""
    rts = np.asarray(rts, complex).copy()
    re = -np.abs(rts.real)
    re = np.minimum(re, -floor * np.maximum(np.abs(rts), floor))
    return re + 1j * rts.imag


def pole_slots_from_groups(quads, single) -> list[float]:
    """Log-section parameters for stable pole groups."""
    out = []
    for q in quads:
        c1, c0 = quad_coefficients(q)
        out += [np.log(c1), np.log(c0)]
    if single is not None:
        out.append(np.log(-single[0].real))
    return out


def zero_slots_from_groups(gain, quads, single) -> list[float]:
    """'zpk' zero slots, gain first, from grouped roots ρ: a factor's coefficients are those of
    (ρ-polynomial) ρ² − (ρ1 + ρ2) ρ + ρ1ρ2 and ρ − ρ0.  'monic' sections: ρ are the zeros,
    (c1, c0) and e, gain the leading coefficient; 'unit' sections: ρ are the *inverse* zeros
    μ = 1/z (a zero at infinity is μ = 0), (β1, β2) = (−(μ1 + μ2), μ1μ2) and β = −μ0, since
    (1 − μ1 s̃)(1 − μ2 s̃) = 1 + β1 s̃ + β2 s̃², gain the numerator's value at s̃ = 0."""
    out = [gain]
    for q in quads:
        out += list(quad_coefficients(q))
    if single is not None:
        out.append(-single[0].real)
    return out


_FAR_INVERSE = 1e12  # an inverse zero standing in for a zero at the origin (which has no β)


def inverse_zeros(num_asc, m: int) -> tuple[float, np.ndarray]:
    """(gain, μ): N(s̃) = gain · Π (1 − μ_i s̃) for a numerator of degree ≤ m (ascending);
    μ = 1/z are the roots of the reversed polynomial (a zero at infinity, a missing leading
    coefficient, is μ = 0).  A zero at the origin (N(0) = 0) has no such factor: μ = 1e12
    stands in for it and the gain is scaled to keep N."""
    num = np.zeros(m + 1)
    num[:min(len(num_asc), m + 1)] = np.asarray(num_asc, float)[:m + 1]
    nz = np.flatnonzero(num)
    if not nz.size:
        return 0.0, np.zeros(m, complex)
    j = int(nz[0])                                   # zeros at the origin
    mu = np.roots(num[j:])                           # num[j:] ascending in s = descending in μ
    gain = float(num[j]) * (-1.0 / _FAR_INVERSE) ** j
    mu = np.concatenate([np.asarray(mu, complex), np.full(j, _FAR_INVERSE + 0j)])
    return gain, mu


def groups_from_theta(structure: Structure, theta, which: str):
    """Root groups of a degree-0 sections/zpk parameter vector, in slot order ('zpk' zeros
    with 'unit' sections: the inverse zeros, as ``zero_slots_from_groups`` reads them)."""
    v = slot_values(structure, theta, 0.0)
    if which == "poles":
        n = structure.n_poles
        secs = section_polys(v, "log_a1", "log_a0", n // 2, "log_c" if n % 2 else None, True)
        odd = n % 2 == 1
    else:
        secs = zero_section_polys(structure, v)
        odd = structure.n_zeros % 2 == 1
        if structure.zero_sections == "unit":        # inverse zeros: roots of the reversed factors
            secs = [sec[::-1] for sec in secs]
    rts = [factor_roots(s) for s in secs]
    if odd:
        return rts[:-1], rts[-1]
    return rts, None


def convert(structure: Structure, theta, form: str, reference_theta=None) -> np.ndarray:
    """Convert a degree-0 parameter vector to another form (same orders).

    ``coefficients`` targets are exact; ``sections``/``zpk`` targets need stable poles
    (unstable ones are reflected).  ``reference_theta`` (in the target form) picks the
    root pairing closest to it, for tracking sections across temperatures.
    """
    if structure.degree != 0:
        raise ValueError("convert works on degree-0 parameter vectors")
    target = structure.with_form(form)
    num, den = polynomials(structure, theta)
    m = structure.n_zeros
    if form == "coefficients":
        return np.concatenate([num, den[:-1]])
    zeros, poles = roots(structure, theta)
    ref_p = ref_z = None
    if reference_theta is not None:
        ref_p = groups_from_theta(target, reference_theta, "poles")
        if form == "zpk":
            ref_z = groups_from_theta(target, reference_theta, "zeros")
    pq, ps = group_roots(stabilise_roots(poles), ref_p)
    pole_part = pole_slots_from_groups(pq, ps)
    if form == "sections":
        return np.concatenate([num, pole_part])
    if target.zero_sections == "unit":
        gain, rho = inverse_zeros(num, m)
    else:
        gain, rho = (float(num[m]) if len(num) > m else 0.0), zeros
    zq, zs = group_roots(rho, ref_z) if m else ([], None)
    return np.concatenate([zero_slots_from_groups(gain, zq, zs), pole_part])
