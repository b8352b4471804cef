"""Model structures: the parametrisations shared by the fitters and the fitted models.

A model is H(s, T) = g_ref · N(s̃, τ) / D(s̃, τ) with s̃ = s/ω_ref (ω_ref in rad/s) and
τ = (T − T_center)/T_scale.  Every *slot* below is a polynomial of degree ``degree`` in τ
(degree 0: temperature-independent), and the parameter vector is the slots' polynomial
coefficients, ascending in τ, slot after slot.

Forms
-----
``coefficients`` (paper (i), seed 000)
    N = Σ b_i s̃^i and D = s̃^n + Σ a_j s̃^j (monic); slots b0..bm, a0..a(n-1).  Stability is
    not structural: when the unconstrained joint optimum is unstable somewhere, the scheduled
    fitter re-solves with Hurwitz (Liénard–Chipart) constraints on a temperature grid, and
    every model is re-checked afterwards on a dense grid.
``sections`` (per-temperature fits)
    N as above; D = Π_k (s̃² + a1_k s̃ + a0_k) · (s̃ + c) with a1 = exp(log_a1), a0 = exp(log_a0),
    c = exp(log_c).  Positive section coefficients ⇔ Hurwitz for degree ≤ 2, so every pole
    is stable for every parameter value; a section holds a complex pair (a1² < 4a0) or two
    real poles (a1² ≥ 4a0) and moves continuously between the two.
``zpk`` (paper (ii), seed 001)
    N = k · Π_k (1 + β1_k s̃ + β2_k s̃²) · (1 + β s̃) with free β1, β2, β (slots zb1_k, zb2_k,
    zb; non-minimum phase allowed; k is the numerator's value at s̃ = 0) and D as in
    ``sections``.  Gain, zero sections and log pole-section coefficients are polynomials in
    T, so a zero or pole pair may turn from complex to real and back at some temperature
    (the discriminant changes sign) without any change of parametrisation, and the poles are
    stable at *every* temperature, not only on a grid.  A zero at infinity is a finite point
    (β2 = 0, or β = 0) reached continuously, with the gain unchanged: the seed 002 optima
    that send a zero out of the band took the former monic sections (s̃² + c1 s̃ + c0), where
    that needs k → 0 with c0 → ∞, 400–1,200 iterations.
    ``zero_sections='monic'``: those former sections, N = k · Π_k (s̃² + c1_k s̃ + c0_k) ·
    (s̃ + e) (slots zc1_k, zc0_k, ze) — models saved with schema version 1 are read in it;
    fits always use ``'unit'``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import polynomial as P

#: The fitter forms, declared once (scheduled fits, the CLI and the scenario schema read this).
FORMS = ("zpk", "coefficients", "sections")
#: 'zpk' zero-section parametrisations: 'unit' (1 + β1 s̃ + β2 s̃², fitted) and 'monic'
#: (s̃² + c1 s̃ + c0, models saved with schema version 1).
ZERO_SECTIONS = ("unit", "monic")
_LOG_BOUND = 30.0  # |log a| ≤ 30 keeps scaled section coefficients within e^±30


@dataclass(frozen=True)
class Structure:
    """Which parametrisation, which orders, which polynomial degree in temperature.

    Parameters
    ----------
    form : {'zpk', 'coefficients', 'sections'}
        The parametrisation (module docstring).
    n_zeros, n_poles : int
        Orders of the numerator and denominator in s (``n_zeros <= n_poles``, ``n_poles >= 1``).
    degree : int
        Polynomial degree of every slot in the scaled temperature τ (0: one temperature).
    zero_sections : {'unit', 'monic'}
        'zpk' only: zero factors 1 + β1 s̃ + β2 s̃² and 1 + β s̃ ('unit', what fits produce), or
        the former s̃² + c1 s̃ + c0 and s̃ + e ('monic', models saved with schema version 1).
    """

    form: str
    n_zeros: int
    n_poles: int
    degree: int = 0
    zero_sections: str = "unit"

    def __post_init__(self):
        if self.form not in FORMS:
            raise ValueError(f"form must be one of {FORMS}, got {self.form!r}")
        if self.zero_sections not in ZERO_SECTIONS:
            raise ValueError(f"zero_sections must be one of {ZERO_SECTIONS}, got {self.zero_sections!r}")
        if self.form != "zpk" and self.zero_sections != "unit":
            raise ValueError(f"zero_sections={self.zero_sections!r} applies to form 'zpk' only, not {self.form!r}")
        for name in ("n_zeros", "n_poles", "degree"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ValueError(f"{name} must be a non-negative integer, got {v!r}")
            object.__setattr__(self, name, int(v))
        if self.n_poles < 1:
            raise ValueError(f"n_poles must be >= 1, got {self.n_poles}")
        if self.n_zeros > self.n_poles:
            raise ValueError(
                f"n_zeros={self.n_zeros} > n_poles={self.n_poles}: only proper models are supported"
            )

    # ------------------------------------------------------------ layout
    @property
    def pole_slots(self) -> list[str]:
        s = []
        for k in range(self.n_poles // 2):
            s += [f"log_a1_{k}", f"log_a0_{k}"]
        if self.n_poles % 2:
            s.append("log_c")
        return s

    @property
    def slots(self) -> list[str]:
        return list(_slots(self.form, self.n_zeros, self.n_poles, self.zero_sections))

    def _slot_names(self) -> list[str]:
        m, n = self.n_zeros, self.n_poles
        num = [f"b{i}" for i in range(m + 1)]
        if self.form == "coefficients":
            return num + [f"a{j}" for j in range(n)]
        if self.form == "sections":
            return num + self.pole_slots
        zs = ["k"]
        p1, p2, single = self.zero_section_slots
        for k in range(m // 2):
            zs += [f"{p1}_{k}", f"{p2}_{k}"]
        if m % 2:
            zs.append(single)
        return zs + self.pole_slots

    @property
    def zero_section_slots(self) -> tuple[str, str, str]:
        """'zpk': the slot prefixes of a zero section's s̃¹ and other coefficient, and the real
        zero's slot: ('zb1', 'zb2', 'zb') for 'unit' sections, ('zc1', 'zc0', 'ze') for 'monic'."""
        return ("zb1", "zb2", "zb") if self.zero_sections == "unit" else ("zc1", "zc0", "ze")

    @property
    def n_coef(self) -> int:
        return self.degree + 1

    @property
    def n_params(self) -> int:
        return len(self.slots) * self.n_coef

    def param_names(self) -> list[str]:
        if self.degree == 0:
            return list(self.slots)
        return [f"{s}:t{q}" for s in self.slots for q in range(self.n_coef)]

    def log_mask(self) -> np.ndarray:
        """True for parameters of log-parametrised (positive) slots."""
        return np.repeat([s.startswith("log_") for s in self.slots], self.n_coef)

    @property
    def zero_slots(self) -> list[str]:
        """The 'zpk' zero-section slots (empty for the other forms)."""
        if self.form != "zpk":
            return []
        p1, p2, single = self.zero_section_slots
        return [s for s in self.slots if s.startswith((f"{p1}_", f"{p2}_")) or s == single]

    def slot_bounds(self, w_min: float = None, w_max: float = None, window: float = 1e3) -> dict:
        """Bounds on the values of the log-slots (pole-section coefficients) and, with a band,
        of the 'zpk' zero-section slots.

        With the scaled band [w_min, w_max], poles are kept within [w_min/window,
        w_max·window] in magnitude and section damping above 1e-4.  Zero sections
        (1 + β1 s̃ + β2 s̃²), (1 + β s̃): |β2| ≤ 1/z², |β1| ≤ 2/z, |β| ≤ 1/z with
        z = w_min/window (zeros at least about z/2 from the origin; a zero at infinity is
        β = 0, inside); 'monic' sections (s̃² + c1 s̃ + c0), (s̃ + e): |c0| ≤ Z², |c1| ≤ 2Z,
        |e| ≤ Z, Z = w_max·window.  Poles and zeros far outside the data band are not
        identifiable and would only drift (a 'unit' section's zero towards the origin needs
        the gain → 0 with β → ∞, as a 'monic' one's towards infinity needs c0 → ∞).
        """
        out = {}
        if w_min is None:
            for s in self.pole_slots:
                out[s] = (-_LOG_BOUND, _LOG_BOUND)
            return out
        lo_p, hi_p = np.log(w_min / window), np.log(w_max * window)
        for s in self.pole_slots:
            if s.startswith("log_a0"):
                out[s] = (2 * lo_p, 2 * hi_p)
            elif s.startswith("log_a1"):
                out[s] = (lo_p + np.log(2e-4), np.log(2.0) + hi_p)
            else:
                out[s] = (lo_p, hi_p)
        p1, p2, _ = self.zero_section_slots
        z = w_max * window if self.zero_sections == "monic" else window / w_min
        for s in self.zero_slots:
            lim = z * z if s.startswith(p2) else (2 * z if s.startswith(p1) else z)
            out[s] = (-lim, lim)
        return out

    def bounds(self, w_min: float = None, w_max: float = None) -> tuple[np.ndarray, np.ndarray]:
        """Parameter bounds: degree 0 applies ``slot_bounds`` directly; otherwise only a
        generous box on the log slots (the scheduled fitter imposes ``slot_bounds`` on a
        temperature grid)."""
        lo, hi = _bounds(self, None if w_min is None else float(w_min), None if w_max is None else float(w_max))
        return lo.copy(), hi.copy()

    def _bounds(self, w_min, w_max):
        lo = np.full(self.n_params, -np.inf)
        hi = np.full(self.n_params, np.inf)
        sb = self.slot_bounds(w_min, w_max) if self.degree == 0 else self.slot_bounds()
        for j, s in enumerate(self.slots):
            if s in sb:
                lo[j * self.n_coef:(j + 1) * self.n_coef] = sb[s][0] if self.degree == 0 else -_LOG_BOUND
                hi[j * self.n_coef:(j + 1) * self.n_coef] = sb[s][1] if self.degree == 0 else _LOG_BOUND
        return lo, hi

    def with_degree(self, degree: int) -> Structure:
        return _structure(self.form, self.n_zeros, self.n_poles, degree, self.zero_sections)

    def with_form(self, form: str) -> Structure:
        """The same orders and degree in another parametrisation.

        Parameters
        ----------
        form : {'zpk', 'coefficients', 'sections'}
            The target form ('zpk': with 'unit' zero sections, whatever this structure's).
        """
        return _structure(form, self.n_zeros, self.n_poles, self.degree)

    def to_dict(self) -> dict:
        d = {"form": self.form, "n_zeros": self.n_zeros, "n_poles": self.n_poles, "degree": self.degree}
        if self.form == "zpk":
            d["zero_sections"] = self.zero_sections
        return d

    # ----------------------------------------------------- slot matrices
    def slot_matrix(self, theta) -> np.ndarray:
        """Parameters as an array (n_slots, degree+1) (numpy only)."""
        return np.asarray(theta, float).reshape(len(self.slots), self.n_coef)


@functools.lru_cache(maxsize=256)
def _slots(form, n_zeros, n_poles, zero_sections="unit") -> tuple:
    """Slot names of a form and orders (computed once)."""
    return tuple(Structure(form, n_zeros, n_poles, 0, zero_sections)._slot_names())


@functools.lru_cache(maxsize=256)
def _structure(form, n_zeros, n_poles, degree, zero_sections="unit") -> Structure:
    """A (frozen, hence shareable) ``Structure``, built and validated once per value."""
    return Structure(form, n_zeros, n_poles, degree, zero_sections)


@functools.lru_cache(maxsize=256)
def _bounds(structure: Structure, w_min, w_max):
    return structure._bounds(w_min, w_max)


# ----------------------------------------------------------------- backends
class NumpyBackend:
    exp = staticmethod(np.exp)
    log = staticmethod(np.log)
    atan2 = staticmethod(np.arctan2)

    @staticmethod
    def ones_like(x):
        return np.ones_like(x)

    @staticmethod
    def zeros_like(x):
        return np.zeros_like(x)


class CasadiBackend:
    def __init__(self):
        import casadi as ca

        self.exp = ca.exp
        self.log = ca.log
        self.atan2 = ca.atan2

    @staticmethod
    def ones_like(x):
        return 0 * x + 1

    @staticmethod
    def zeros_like(x):
        return 0 * x


def _cmul(ar, ai, br, bi):
    return ar * br - ai * bi, ar * bi + ai * br


def evaluate(structure: Structure, theta, w, tau, be=NumpyBackend):
    """Real and imaginary parts of N(jw̃) and D(jw̃) at points (w̃, τ).

    ``w`` (= ω/ω_ref) and ``tau`` are vectors of the backend's type (numpy arrays, or
    CasADi columns, possibly symbolic); ``theta`` a numpy vector or a CasADi symbol.
    Returns ``(Nr, Ni, Dr, Di)``.
    """
    nc = structure.n_coef
    slots = structure.slots
    ones = be.ones_like(w)
    tpow = [ones]
    for _ in range(1, nc):
        tpow.append(tpow[-1] * tau)

    def slot(name):
        j = slots.index(name) * nc
        v = theta[j] * ones
        for q in range(1, nc):
            v = v + theta[j + q] * tpow[q]
        return v

    m, n = structure.n_zeros, structure.n_poles
    w2 = w * w

    def linear_poly(prefix, count, monic_degree=None):
        re, im = be.zeros_like(w), be.zeros_like(w)
        wp = ones
        for i in range(max(count, (monic_degree or 0) + 1)):
            if i < count:
                v = wp * slot(f"{prefix}{i}")
            elif i == monic_degree:
                v = wp
            else:
                v = None
            if v is not None:
                r = i % 4
                if r == 0:
                    re = re + v
                elif r == 1:
                    im = im + v
                elif r == 2:
                    re = re - v
                else:
                    im = im - v
            wp = wp * w
        return re, im

    def sections(prefix1, prefix0, count, single, log):
        re, im = ones, be.zeros_like(w)
        f = be.exp if log else (lambda x: x)
        for k in range(count):
            c1, c0 = f(slot(f"{prefix1}_{k}")), f(slot(f"{prefix0}_{k}"))
            re, im = _cmul(re, im, c0 - w2, c1 * w)
        if single is not None:
            re, im = _cmul(re, im, f(slot(single)), w)
        return re, im

    def unit_sections(prefix1, prefix2, count, single):
        re, im = ones, be.zeros_like(w)
        for k in range(count):        # 1 + β1 jw + β2 (jw)²
            re, im = _cmul(re, im, ones - slot(f"{prefix2}_{k}") * w2, slot(f"{prefix1}_{k}") * w)
        if single is not None:
            re, im = _cmul(re, im, ones, slot(single) * w)
        return re, im

    if structure.form == "zpk":
        p1, p2, single = structure.zero_section_slots
        if structure.zero_sections == "unit":
            zr, zi = unit_sections(p1, p2, m // 2, single if m % 2 else None)
        else:
            zr, zi = sections(p1, p2, m // 2, single if m % 2 else None, log=False)
        k = slot("k")
        nr, ni = k * zr, k * zi
    else:
        nr, ni = linear_poly("b", m + 1)
    if structure.form == "coefficients":
        dr, di = linear_poly("a", n, monic_degree=n)
    else:
        dr, di = sections("log_a1", "log_a0", n // 2, "log_c" if n % 2 else None, log=True)
    return nr, ni, dr, di


def response(structure: Structure, theta, w, tau) -> np.ndarray:
    """Complex N/D at scaled frequencies w̃ and scaled temperatures τ (numpy)."""
    w = np.asarray(w, float)
    tau = np.broadcast_to(np.asarray(tau, float), w.shape)
    nr, ni, dr, di = evaluate(structure, np.asarray(theta, float), w, tau)
    return (nr + 1j * ni) / (dr + 1j * di)


# ------------------------------------------------------- polynomials at τ
def slot_values(structure: Structure, theta, tau: float) -> dict:
    mat = structure.slot_matrix(theta)
    tp = float(tau) ** np.arange(structure.n_coef)
    return dict(zip(structure.slots, mat @ tp))


def section_polys(vals, p1, p0, count, single, log):
    f = np.exp if log else (lambda x: x)
    out = []
    for k in range(count):
        out.append(np.array([f(vals[f"{p0}_{k}"]), f(vals[f"{p1}_{k}"]), 1.0]))
    if single is not None:
        out.append(np.array([f(vals[single]), 1.0]))
    return out


def zero_section_polys(structure: Structure, vals) -> list:
    """'zpk': the zero factors' coefficients in s̃ (ascending) from slot values: [1, β1, β2]
    and [1, β] ('unit'), [c0, c1, 1] and [e, 1] ('monic')."""
    m = structure.n_zeros
    p1, p2, single = structure.zero_section_slots
    if structure.zero_sections == "monic":
        return section_polys(vals, p1, p2, m // 2, single if m % 2 else None, False)
    out = [np.array([1.0, vals[f"{p1}_{k}"], vals[f"{p2}_{k}"]]) for k in range(m // 2)]
    if m % 2:
        out.append(np.array([1.0, vals[single]]))
    return out


def polynomials(structure: Structure, theta, tau: float = 0.0):
    """Numerator and monic denominator coefficients in s̃, ascending powers, at τ."""
    v = slot_values(structure, theta, tau)
    m, n = structure.n_zeros, structure.n_poles
    if structure.form == "zpk":
        num = np.array([v["k"]])
        for sec in zero_section_polys(structure, v):
            num = P.polymul(num, sec)
        num = np.pad(num, (0, m + 1 - num.size))      # polymul trims a zero leading β
    else:
        num = np.array([v[f"b{i}"] for i in range(m + 1)])
    if structure.form == "coefficients":
        den = np.append([v[f"a{j}"] for j in range(n)], 1.0)
    else:
        den = np.array([1.0])
        for sec in section_polys(v, "log_a1", "log_a0", n // 2, "log_c" if n % 2 else None, True):
            den = P.polymul(den, sec)
    return np.asarray(num, float), np.asarray(den, float)


def denominators(structure: Structure, theta, taus) -> np.ndarray:
    """Monic denominator coefficients in s̃ (ascending) at many scaled temperatures at once,
    shape (len(taus), n_poles + 1); the same numbers as ``polynomials(...)[1]`` per τ."""
    taus = np.atleast_1d(np.asarray(taus, float))
    vals = structure.slot_matrix(theta) @ (taus[None, :] ** np.arange(structure.n_coef)[:, None])
    v = dict(zip(structure.slots, vals))                       # slot -> (K,)
    n, k = structure.n_poles, taus.size
    if structure.form == "coefficients":
        return np.column_stack([v[f"a{j}"] for j in range(n)] + [np.ones(k)])
    den = np.ones((k, 1))
    sections = [(np.exp(v[f"log_a0_{i}"]), np.exp(v[f"log_a1_{i}"]), np.ones(k)) for i in range(n // 2)]
    if n % 2:
        sections.append((np.exp(v["log_c"]), np.ones(k)))
    for sec in sections:
        out = np.zeros((k, den.shape[1] + len(sec) - 1))
        for j, c in enumerate(sec):
            out[:, j:j + den.shape[1]] += den * c[:, None]
        den = out
    return den


def section_max_real_part(structure: Structure, theta, taus) -> np.ndarray:
    """Largest real part of the poles in s̃ of a section denominator ('sections', 'zpk') at
    many scaled temperatures at once, shape (len(taus),).  Each section s̃² + a1 s̃ + a0 in
    closed form: −a1/2 for a complex pair, else the root nearer zero, a0/q with
    q = −(a1 + sign(a1)·√disc)/2 (cancellation-free, as ``factor_roots``); (s̃ + c): −c."""
    if structure.form == "coefficients":
        raise ValueError("section_max_real_part needs a section denominator ('sections' or 'zpk')")
    taus = np.atleast_1d(np.asarray(taus, float))
    ix = {s: i for i, s in enumerate(structure.slots)}
    n = structure.n_poles
    mat = structure.slot_matrix(theta)
    tp = taus[None, :] ** np.arange(structure.n_coef)[:, None]          # (n_coef, K)
    best = np.full(taus.size, -np.inf)
    if n // 2:
        a1 = np.exp(mat[[ix[f"log_a1_{k}"] for k in range(n // 2)]] @ tp)   # (sections, K)
        a0 = np.exp(mat[[ix[f"log_a0_{k}"] for k in range(n // 2)]] @ tp)
        disc = a1 * a1 - 4 * a0
        with np.errstate(divide="ignore", invalid="ignore"):
            q = -(a1 + np.copysign(np.sqrt(np.maximum(disc, 0.0)), a1)) / 2
            near = np.where(q != 0.0, a0 / q, 0.0)
        best = np.maximum(best, np.where(disc < 0, -a1 / 2, np.maximum(q, near)).max(axis=0))
    if n % 2:
        best = np.maximum(best, -np.exp(mat[ix["log_c"]] @ tp))
    return best


def factor_roots(poly_asc) -> np.ndarray:
    """Roots of c0 + c1 s + s² (or c0 + s); real pairs by the cancellation-free formula
    q = −(c1 + sign(c1)·√disc)/2, roots q and c0/q (a root much smaller than the other is
    otherwise lost to rounding and can come out as exactly 0)."""
    if len(poly_asc) == 3:
        c0, c1 = float(poly_asc[0]), float(poly_asc[1])
        disc = c1 * c1 - 4 * c0
        if disc < 0:
            im = np.sqrt(-disc) / 2
            return np.array([complex(-c1 / 2, im), complex(-c1 / 2, -im)])
        q = -(c1 + np.copysign(np.sqrt(disc), c1)) / 2
        if q == 0.0:
            return np.zeros(2, complex)
        return np.array([complex(q), complex(c0 / q)])
    return np.array([-poly_asc[0] + 0j])


def finite_roots(poly_asc) -> np.ndarray:
    """Finite roots of a0 + a1 s + a2 s² (or a0 + a1 s) whose leading coefficient may be 0
    (a root at infinity, left out), cancellation-free like ``factor_roots``: for real roots,
    q = −(a1 + sign(a1)·√disc)/2 and the roots q/a2 and a0/q."""
    a = [float(c) for c in poly_asc]
    if len(a) == 2:
        return np.array([complex(-a[0] / a[1])]) if a[1] != 0.0 else np.array([], complex)
    a0, a1, a2 = a
    if a2 == 0.0:
        return finite_roots([a0, a1])
    disc = a1 * a1 - 4 * a0 * a2
    if disc < 0:
        im = np.sqrt(-disc) / (2 * abs(a2))
        return np.array([complex(-a1 / (2 * a2), im), complex(-a1 / (2 * a2), -im)])
    q = -(a1 + np.copysign(np.sqrt(disc), a1)) / 2
    if q == 0.0:
        return np.zeros(2, complex)
    return np.array([complex(q / a2), complex(a0 / q)])


def roots(structure: Structure, theta, tau: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(zeros, poles) in s̃ at τ; sections are solved in closed form ('zpk': a zero at
    infinity, β2 = 0 or β = 0, is left out)."""
    v = slot_values(structure, theta, tau)
    n = structure.n_poles
    num, den = polynomials(structure, theta, tau)
    if structure.form == "zpk":
        secs = zero_section_polys(structure, v)
        zeros = np.concatenate([finite_roots(s) for s in secs]) if secs else np.array([], complex)
    else:
        zeros = np.roots(num[::-1]) if np.any(num) else np.array([], complex)
    if structure.form == "coefficients":
        poles = np.roots(den[::-1])
    else:
        secs = section_polys(v, "log_a1", "log_a0", n // 2, "log_c" if n % 2 else None, True)
        poles = np.concatenate([factor_roots(s) for s in secs])
    return zeros.astype(complex), poles.astype(complex)


def hurwitz_matrix(coeffs_desc):
    """Hurwitz matrix of a polynomial given by coefficients in descending powers.

    Works for numbers and CasADi symbols (returns a nested list)."""
    n = len(coeffs_desc) - 1

    def c(k):
        return coeffs_desc[k] if 0 <= k <= n else 0

    return [[c(2 * j - i + 1) for j in range(n)] for i in range(n)]
