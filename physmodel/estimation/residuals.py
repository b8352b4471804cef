"""Standardised residuals of a model against a :class:`~physmodel.data.sweep.FrequencySweep`
(or scalar observations, :class:`SweepResiduals` / :class:`ObservationResiduals`).

For each line the relative error ln(G_data/G_model) is split into log-magnitude and phase:
``r = [ln|G_d/G_m| / σ_ln, wrap(∠G_d − ∠G_m) / σ_φ]`` with σ_ln = magnitude_std_db·ln10/20 [Np] and
σ_φ = phase_std_deg·π/180 [rad] from the sweep (discrepancy.md §1).  The cost ½Σr² of a correct
model averages F − nθ/2 (F lines, nθ fitted parameters) with spread ≈ sqrt(F − nθ/2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..data.sweep import FrequencySweep
from ..errors import DataFormatError, IPMCError

#: Relative standard deviation assumed per line (log-magnitude [Np] and phase [rad]) when a sweep
#: carries no per-line uncertainty; the covariance is then rescaled by the fitted residual variance.
FALLBACK_RELATIVE_STD = 0.01

def noise_std(data: FrequencySweep) -> tuple[np.ndarray, np.ndarray, bool]:
    """Per-line σ_ln [Np] and σ_φ [rad] of a sweep, and whether they are the fallback (estimated)."""
    n = data.frequency_hz.size
    if data.magnitude_std_db is None:
        return np.full(n, FALLBACK_RELATIVE_STD), np.full(n, FALLBACK_RELATIVE_STD), True
    s_ln = data.magnitude_std_db * (math.log(10.0) / 20.0)
    s_ph = np.radians(data.phase_std_deg)
    bad = np.flatnonzero((s_ln <= 0) | (s_ph <= 0))
    if bad.size:
        raise DataFormatError(f"per-line standard deviations must be > 0 to weight a fit; line(s) "
                              f"{bad[:5].tolist()} have magnitude_std_db={data.magnitude_std_db[bad[:5]].tolist()}, "
                              f"phase_std_deg={data.phase_std_deg[bad[:5]].tolist()}")
    return s_ln, s_ph, False


def standardised_residuals(model_response, data: FrequencySweep, s_ln, s_ph) -> np.ndarray:
    """:func:`residuals` with given per-line σ_ln [Np] and σ_φ [rad] (see :func:`noise_std`);
    an error, never NaN, where the model response is zero or not finite."""
    G = np.asarray(model_response, dtype=complex)
    n = data.response.size
    if G.shape[-1] != n:
        raise IPMCError(f"model response has {G.shape[-1]} values per set for {n} data lines")
    out = np.empty(G.shape[:-1] + (2 * n,))
    with np.errstate(all="ignore"):
        q = data.response / G
        # ln q = ln|q| + i arg q (principal branch), without the much slower complex logarithm;
        # written into the halves of one array (no concatenation)
        a = np.abs(q)
        np.divide(np.log(a, out=a), s_ln, out=out[..., :n])
        # arg q = np.angle(q), on contiguous copies of the parts: numpy's arctan2 is one function for
        # strided and contiguous input, which it reads faster (the same values bit for bit)
        ph = np.arctan2(np.ascontiguousarray(q.imag), np.ascontiguousarray(q.real))
        np.divide(ph, s_ph, out=out[..., n:])
        # one sum, not an elementwise test: finite unless some residual is not (or it overflows)
        finite = math.isfinite(out.sum()) or bool(np.all(np.isfinite(out)))
    if not finite:
        bad = ~np.isfinite(G) | (G == 0)
        if not np.any(bad):     # a data value that is zero or not finite: FrequencySweep refuses these
            bad = ~np.isfinite(q) | (q == 0)
        raise IPMCError(f"model response is zero or not finite at {int(bad.sum())} line(s) "
                        f"(first at frequency {data.frequency_hz[np.flatnonzero(bad.reshape(-1, n).any(0))[0]]:g} Hz)")
    return out


def residuals(model_response: np.ndarray, data: FrequencySweep) -> np.ndarray:
    """Standardised real residuals ``[ln|G_d/G_m|/σ_ln (N), wrap(∠G_d − ∠G_m)/σ_φ (N)]``.

    ``model_response``: complex (N,) in the sweep's units (or (n_sets, N) → (n_sets, 2N)).
    Without per-line standard deviations the fallback σ = :data:`FALLBACK_RELATIVE_STD` is used.
    """
    s_ln, s_ph, _ = noise_std(data)
    return standardised_residuals(model_response, data, s_ln, s_ph)


def weighted_cost(model_response, data: FrequencySweep) -> float:
    """½·Σ r² of :func:`residuals`; for a correct model its mean is ≈ F − nθ/2 (F lines)."""
    r = residuals(model_response, data)
    return float(0.5 * np.sum(r * r))


def gauss_newton_covariance(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Newton covariance (JᵀJ)⁻¹ of the fitted coordinates, via the SVD of the (standardised)
    Jacobian ``J`` (n_residuals, n_parameters); returns (cov, singular values) [-]."""
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    tiny = s.max() * 1e-14 if s.size and s.max() > 0 else 1e-300
    inv = 1.0 / np.maximum(s, tiny) ** 2
    return (Vt.T * inv) @ Vt, s


#: A cost whose χ² tail probability is below this is inconsistent with the declared noise.
GOF_ALPHA = 1e-3
#: With estimated noise (no per-line standard deviations) the residuals imply a relative noise per
#: line; above this (20 %: 1.7 dB in magnitude, 11° in phase) the scatter is a misfit, not noise.
MAX_ESTIMATED_RELATIVE_NOISE = 0.2


@dataclass(frozen=True)
class GoodnessOfFit:
    """Whether a fitted model is consistent with its data.

    ``chi2`` = 2·cost = Σr² of the standardised residuals on ``dof`` = (residuals − parameters)
    degrees of freedom; ``reduced_chi2`` = chi2/dof (its square root is the Birge ratio that widens
    intervals under ``accept_misfit``).  Declared noise: ``p_value`` = P(χ²_dof ≥ chi2) and
    ``adequate`` = p ≥ ``alpha``.  Estimated noise (the fallback σ): χ² is not informative, so
    ``relative_noise`` = FALLBACK_RELATIVE_STD·sqrt(reduced_chi2) is compared with
    :data:`MAX_ESTIMATED_RELATIVE_NOISE` and ``p_value`` is None.
    """

    adequate: bool
    chi2: float
    dof: int
    reduced_chi2: float
    p_value: float | None
    relative_noise: float | None
    reason: str

    def to_dict(self) -> dict:
        num = lambda v: None if v is None or not math.isfinite(v) else float(v)  # noqa: E731
        return {"adequate": bool(self.adequate), "chi2": num(self.chi2), "dof": int(self.dof),
                "reduced_chi2": num(self.reduced_chi2), "p_value": num(self.p_value),
                "relative_noise": num(self.relative_noise), "reason": self.reason}


def goodness_of_fit(cost: float, n_residuals: int, n_parameters: int, noise_estimated: bool,
                    alpha: float = GOF_ALPHA) -> GoodnessOfFit:
    """Test a weighted least-squares cost ½Σr² against its χ² expectation (see :class:`GoodnessOfFit`)."""
    # the χ² survival function: scipy.stats.chi2.sf's own, without its layer
    from scipy.special import chdtrc

    dof = int(n_residuals - n_parameters)
    x = 2.0 * float(cost)
    if dof <= 0 or not math.isfinite(x):
        return GoodnessOfFit(dof > 0 and math.isfinite(x), x, dof, float("nan"), None, None,
                             "not testable: " + ("no residual degrees of freedom" if dof <= 0 else "the cost is not finite"))
    red = x / dof
    if not noise_estimated:
        p = float(chdtrc(dof, x))
        ok = p >= alpha
        return GoodnessOfFit(ok, x, dof, red, p, None,
                             f"chi2 = {x:.4g} on {dof} degrees of freedom (expected {dof} ± {math.sqrt(2 * dof):.3g}), "
                             f"p = {p:.2g}: " + ("consistent with the declared noise" if ok else
                                                 f"the model does not fit the data within the declared noise (p < {alpha:g})"))
    rel = FALLBACK_RELATIVE_STD * math.sqrt(red)
    ok = rel <= MAX_ESTIMATED_RELATIVE_NOISE
    return GoodnessOfFit(ok, x, dof, red, None, rel,
                         f"no per-line standard deviations: the residuals imply {rel:.3g} relative noise per line "
                         f"(ln-magnitude, phase in rad); " + ("plausible as measurement noise" if ok else
                         f"above {MAX_ESTIMATED_RELATIVE_NOISE:g} this is a misfit, not noise: the model does not fit the data"))


class SweepResiduals:
    """The least-squares engine's view of a :class:`~physmodel.data.sweep.FrequencySweep`: 2N
    residuals ``[ln|G_d/G_m|/σ_ln, arg(G_d/G_m)/σ_φ]`` of N complex predictions per set, and the
    columns of their Jacobian that a predictor knows by the chain rule."""

    def __init__(self, data: FrequencySweep):
        self.data = data
        self.s_ln, self.s_ph, self.estimated = noise_std(data)
        self.n_values = data.frequency_hz.size
        self.size = 2 * self.n_values
        self.frequency_hz = data.frequency_hz
        self.band_hz = (float(data.frequency_hz.min()), float(data.frequency_hz.max()))
        self.temperatures_c = data.temperatures().tolist()
        self.what = f"{self.n_values} lines (2 residuals each)"

    def __call__(self, G) -> np.ndarray:
        """(n_sets, 2N) standardised residuals of predictions ``G`` (n_sets, N)."""
        return standardised_residuals(G, self.data, self.s_ln, self.s_ph)

    def scaled_column(self, column: np.ndarray, c: np.ndarray) -> np.ndarray:
        """∂r/∂z_k for a parameter acting as c(line) times another (``column`` its ∂r/∂z)."""
        return column * np.tile(c, 2)

    def constant_column(self, dlnG: complex) -> np.ndarray:
        """∂r/∂z_k for ∂ln G/∂z_k = ``dlnG`` at every line."""
        return np.concatenate([np.full(self.s_ln.size, -dlnG.real) / self.s_ln,
                               np.full(self.s_ph.size, -dlnG.imag) / self.s_ph])

    def ln_sensitivity(self, J: np.ndarray) -> np.ndarray:
        """|∂ln G/∂z| per line (N, n) from the standardised Jacobian (2N, n)."""
        n = self.n_values
        return np.sqrt((J[:n] * self.s_ln[:, None]) ** 2 + (J[n:] * self.s_ph[:, None]) ** 2)


class ObservationResiduals:
    """The engine's view of :class:`~physmodel.estimation.observations.ScalarObservations`: N residuals
    ln|y_model/y|/σ_ln of N predictions per set (the real part of a complex prediction)."""

    def __init__(self, data):
        self.data = data
        self.s_ln, self.estimated = data.sigma_ln, False
        self.n_values = self.size = data.values.size
        self.frequency_hz = None
        self.band_hz = (float("nan"), float("nan"))
        self.temperatures_c = [] if data.temperatures_c is None else data.temperatures_c.tolist()
        self.what = f"{self.n_values} scalar observations"

    def __call__(self, y) -> np.ndarray:
        y = np.asarray(y)
        y = y.real if np.iscomplexobj(y) else y
        if y.shape[-1] != self.n_values:
            raise IPMCError(f"model returned {y.shape[-1]} values per set for {self.n_values} observations")
        with np.errstate(all="ignore"):
            out = np.log(np.abs(y / self.data.values)) / self.s_ln
        if not np.all(np.isfinite(out)):
            bad = np.flatnonzero((~np.isfinite(out)).reshape(-1, self.n_values).any(0))
            raise IPMCError(f"model value is zero or not finite at observation(s) "
                            f"{[self.data.labels[i] for i in bad[:5]]}")
        return out

    def scaled_column(self, column: np.ndarray, c: np.ndarray) -> np.ndarray:
        """As :meth:`SweepResiduals.scaled_column`."""
        return column * c

    def constant_column(self, dlnG: complex) -> np.ndarray:
        """As :meth:`SweepResiduals.constant_column` (the real part acts)."""
        return np.full(self.n_values, dlnG.real) / self.s_ln

    def ln_sensitivity(self, J: np.ndarray) -> np.ndarray:
        """|∂ln y/∂z| per observation (N, n)."""
        return np.abs(J * self.s_ln[:, None])


#: A parameter whose move across a tenth of its scaled range changes no standardised residual by
#: more than this has zero sensitivity: the data do not depend on it (held, not fitted).
ZERO_SENSITIVITY = 1e-6
ZERO_REASON = (f"the data do not depend on it (zero sensitivity: a move across a tenth of its bounds changes no "
               f"residual by more than {ZERO_SENSITIVITY:g} σ)")


def tenth_moves(free, z) -> np.ndarray:
    """Rows (1 + n, n) of scaled coordinates: ``z``, then each parameter moved by a tenth of its
    scaled range (away from its nearer bound) [-]."""
    lo = np.array([fp.z_bounds[0] for fp in free])
    hi = np.array([fp.z_bounds[1] for fp in free])
    step = np.where(z + 0.1 * (hi - lo) <= hi, 0.1, -0.1) * (hi - lo)
    return np.vstack([z, z + np.diag(step)])


def insensitive(R: np.ndarray) -> list[int]:
    """Indices of the parameters whose move (rows 1.. of ``R``, the residuals at
    :func:`tenth_moves`) changes no residual by more than :data:`ZERO_SENSITIVITY`."""
    return np.flatnonzero(np.abs(R[1:] - R[0]).max(axis=1) <= ZERO_SENSITIVITY).tolist()


def residual_model(data):
    """:class:`SweepResiduals` or :class:`ObservationResiduals` for ``data``; anything else is an
    IPMCError."""
    from .observations import ScalarObservations

    if isinstance(data, FrequencySweep):
        return SweepResiduals(data)
    if isinstance(data, ScalarObservations):
        return ObservationResiduals(data)
    raise IPMCError(f"data must be a FrequencySweep or ScalarObservations, got {type(data).__name__}")
