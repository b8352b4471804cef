"""The result every FRF estimator returns (:class:`FRFEstimate`) and what the estimators share:
checks of the input and output samples, the σ of a line from its coherence (Welch, from the exact
distribution of the estimate) or from the scatter of per-period phasors (periodic excitation,
stepped sine), and the coherence a line needs to stand out of noise (per line, or for all lines of
an estimate together).  The estimators are :mod:`physmodel.estimation.frf` (Welch, and the front
door that reads the excitation), :mod:`physmodel.estimation.periodic` and
:mod:`physmodel.estimation.stepped`; their statistics are described in
:mod:`physmodel.estimation.frf`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cache

import numpy as np

from ..data.sweep import FrequencySweep
from ..errors import IPMCError

NEPER_TO_DB = 20.0 / math.log(10.0)
BLOCK_SAMPLES = 1 << 20
class FRFWarning(UserWarning):
    """A problem an FRF estimate was made despite (clipping below the refusal limit, low coherence,
    steps not used); the same text is in ``FRFEstimate.warnings``."""


#: Default false-alarm probability of the coherence threshold (:func:`coherence_threshold`).
COHERENCE_ALPHA = 0.01


# ----------------------------------------------------------------------------------- inputs
def as_signal(x, name: str, n: int | None = None):
    """``x`` when it is 1-D (of ``n`` samples, if given); an :class:`IPMCError` naming ``name`` otherwise."""
    if np.ndim(x) != 1:
        raise IPMCError(f"{name} must be 1-D samples, got shape {np.shape(x)}")
    if n is not None and len(x) != n:
        raise IPMCError(f"{name} has {len(x)} samples; the input has {n}")
    return x


def as_outputs(y, n: int) -> list:
    """Output channels as a list of 1-D sample arrays (views, not copies)."""
    if isinstance(y, (list, tuple)):
        outs = list(y)
    elif np.ndim(y) == 1:
        outs = [y]
    elif np.ndim(y) == 2:
        outs = [y[i] for i in range(np.shape(y)[0])]
    else:
        raise IPMCError(f"y must be (n,) or (channels, n) samples, got shape {np.shape(y)}")
    if not outs:
        raise IPMCError("y: no output channels")
    return [as_signal(v, f"y[{i}]", n) for i, v in enumerate(outs)]


def channel_names(names, units, k: int, default: str):
    """Names and units of ``k`` output channels (``default``, ``default0``... and "1" when not given)."""
    names = tuple(names) if names is not None else ((default,) if k == 1 else tuple(f"{default}{i}" for i in range(k)))
    units = tuple(units) if units is not None else ("1",) * k
    if len(names) != k or len(units) != k:
        raise IPMCError(f"output_names/output_units: {len(names)} names and {len(units)} units for {k} output channels")
    return names, units


def finite_block(x, name: str, offset: int) -> np.ndarray:
    """A block of samples as floats; an :class:`IPMCError` naming the first non-finite samples
    (indices counted from ``offset``)."""
    x = np.asarray(x, dtype=float)
    if not np.all(np.isfinite(x)):
        bad = np.flatnonzero(~np.isfinite(x))[:5] + offset
        raise IPMCError(f"{name} contains NaN or inf at samples {bad.tolist()}")
    return x


# ----------------------------------------------------------------------------------- result
@dataclass(frozen=True)
class FRFEstimate:
    """Estimated frequency response of one input to one or more output channels.

    Attributes
    ----------
    frequency_hz : (n_f,) ndarray          lines, increasing. [Hz]
    response : (n_out, n_f) complex ndarray   output/input in ``output_units[i]/input_unit``
    magnitude_std_db : (n_out, n_f) ndarray   σ of 20·log10|H|. [dB]
    phase_std_deg : (n_out, n_f) ndarray      σ of the phase. [deg]
    coherence : (n_out, n_f) ndarray or None  ordinary coherence γ² over the segments or periods
        (None for an estimate made before the coherence was kept)
    n_averages : (n_f,) ndarray            segments (Welch) or whole periods (periodic, stepped sine) per line
    method : str                           "h1", "h2", "periodic_h1", "periodic_h2" or "stepped_sine"
    input_name, input_unit : str
    output_names, output_units : tuple of str
    settings : dict                        estimator settings (fs, nperseg, window, settle, the detected
        excitation, ``coherence_threshold``, ...)
    warnings : tuple of str                problems found on the way (clipping, low coherence, an
        unchecked transient); :meth:`to_sweep` copies them into the sweep's metadata
    """

    frequency_hz: np.ndarray
    response: np.ndarray
    magnitude_std_db: np.ndarray
    phase_std_deg: np.ndarray
    coherence: np.ndarray | None
    n_averages: np.ndarray
    method: str
    input_name: str = "input"
    input_unit: str = "1"
    output_names: tuple = ("output",)
    output_units: tuple = ("1",)
    settings: dict = field(default_factory=dict)
    warnings: tuple = ()

    @property
    def coherence_threshold(self) -> float | None:
        """The coherence a line needs to stand out of noise (``settings['coherence_threshold']``, set
        by the estimators from their number of averages and, for Welch, of lines; see
        :func:`coherence_threshold`)."""
        v = self.settings.get("coherence_threshold")
        return None if v is None else float(v)

    def significant(self) -> np.ndarray:
        """(n_out, n_f) bool: lines whose coherence reaches :attr:`coherence_threshold` (all True
        when the estimate has no coherence or no threshold)."""
        if self.coherence is None or self.coherence_threshold is None:
            return np.ones(self.response.shape, dtype=bool)
        return self.coherence >= self.coherence_threshold

    def index(self, output: str | int | None) -> int:
        """Row of an output channel (by name or index; None = the only one)."""
        if output is None:
            if len(self.output_names) != 1:
                raise IPMCError(f"output: the estimate has channels {list(self.output_names)}; name one")
            return 0
        if isinstance(output, (int, np.integer)) and 0 <= output < len(self.output_names):
            return int(output)
        if output in self.output_names:
            return self.output_names.index(output)
        raise IPMCError(f"output {output!r} is not a channel of the estimate; expected one of {list(self.output_names)}")

    def channel(self, output: str | int | None) -> FRFEstimate:
        """The estimate for one output channel."""
        i = self.index(output)
        return replace(self, response=self.response[i:i + 1], magnitude_std_db=self.magnitude_std_db[i:i + 1],
                       phase_std_deg=self.phase_std_deg[i:i + 1],
                       coherence=None if self.coherence is None else self.coherence[i:i + 1],
                       output_names=(self.output_names[i],), output_units=(self.output_units[i],))

    def reciprocal(self, output: str | int | None = None) -> FRFEstimate:
        """input/output of one channel (e.g. impedance V/I from the admittance I/V estimated with the
        voltage as reference).  σ of ln|H| and of the phase are unchanged by inversion."""
        c = self.channel(output)
        return replace(c, response=1.0 / c.response, input_name=c.output_names[0], input_unit=c.output_units[0],
                       output_names=(c.input_name,), output_units=(c.input_unit,),
                       settings={**c.settings, "reciprocal": True})

    def to_sweep(self, temperature_c: float, output: str | int | None = None, *,
                 min_coherence: float | str | None = None,
                 band_hz: tuple | None = None, max_std_db: float | None = None, quantity: str | None = None,
                 metadata: dict | None = None) -> FrequencySweep:
        """A :class:`~physmodel.sweep.FrequencySweep` of one channel at ``temperature_c`` [°C].

        ``min_coherence`` (a number, or ``"auto"`` for :attr:`coherence_threshold`), ``band_hz`` [Hz]
        and ``max_std_db`` [dB] drop lines (e.g. the unexcited
        bins of a multisine, or lines whose log-magnitude error is too large to be Gaussian: beyond
        about 1 dB the ±2σ interval of 20·log10|H| covers less than 95 %, see the module doc); a kept
        line without a finite response and σ is an error naming its frequency.
        """
        if not math.isfinite(float(temperature_c)):
            raise IPMCError(f"temperature_c={temperature_c!r} must be a finite number [°C]")
        i = self.index(output)
        f = self.frequency_hz
        keep = np.ones(f.size, dtype=bool)
        if band_hz is not None:
            lo, hi = (float(v) for v in band_hz)
            if not lo <= hi:
                raise IPMCError(f"band_hz={band_hz!r} must be (low, high) with low <= high [Hz]")
            keep &= (f >= lo) & (f <= hi)
        if isinstance(min_coherence, str):
            if min_coherence != "auto":
                raise IPMCError(f"min_coherence={min_coherence!r}; expected a number in [0, 1] or 'auto'")
            min_coherence = self.coherence_threshold
        if min_coherence is not None:
            if self.coherence is None:
                raise IPMCError(f"min_coherence: a {self.method} estimate has no coherence; use band_hz")
            with np.errstate(invalid="ignore"):
                keep &= self.coherence[i] >= float(min_coherence)
        if max_std_db is not None:
            if not float(max_std_db) > 0:
                raise IPMCError(f"max_std_db={max_std_db!r} must be > 0 [dB]")
            with np.errstate(invalid="ignore"):
                keep &= self.magnitude_std_db[i] <= float(max_std_db)
        if not keep.any():
            raise IPMCError(f"no lines left after band_hz={band_hz!r}, min_coherence={min_coherence!r} "
                            f"and max_std_db={max_std_db!r}")
        H, sm, sp = self.response[i, keep], self.magnitude_std_db[i, keep], self.phase_std_deg[i, keep]
        bad = ~(np.isfinite(H) & (H != 0) & np.isfinite(sm) & np.isfinite(sp))
        if bad.any():
            raise IPMCError(f"lines at {f[keep][bad][:5].tolist()} Hz have no finite response or σ "
                            f"(no excitation there?); drop them with min_coherence=, band_hz= or the "
                            f"estimator's frequencies_hz=")
        meta = {"source": f"physmodel.estimation.frf.{self.method}", "method": self.method,
                **{k: str(v) for k, v in self.settings.items()}}
        if self.warnings:
            meta["warnings"] = " | ".join(self.warnings)
        if quantity is not None:
            meta["quantity"] = quantity
        meta.update({k: str(v) for k, v in (metadata or {}).items()})
        return FrequencySweep(np.full(H.size, float(temperature_c)), f[keep], H, sm, sp, self.input_name,
                              self.input_unit, self.output_names[i], self.output_units[i], meta)


def sigma_from_coherence(coh: np.ndarray, dof: float) -> tuple[np.ndarray, np.ndarray]:
    """First-order σ [dB], σ [deg] of an FRF line from coherence and degrees of freedom
    (Bendat & Piersol 9.90): ``σ_ln = σ_φ = sqrt((1 − γ²)/(2 ν γ²))``; see :func:`sigma_exact`."""
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.sqrt(np.clip(1.0 - coh, 0.0, None) / (2.0 * dof * coh))
    s = np.where(coh > 0, s, np.inf)
    return NEPER_TO_DB * s, np.degrees(s)


#: Gauss–Legendre nodes and weights on (0, 1) for the expectation over |Z|² (:func:`sigma_exact`).
_GL_T, _GL_W = np.polynomial.legendre.leggauss(96)
_GL_T, _GL_W = 0.5 * (_GL_T + 1.0), 0.5 * _GL_W


@cache
def _phase_beyond_table() -> tuple[np.ndarray, np.ndarray]:
    """``u = 1/ρ`` and the mean over θ of arg²(1 − ρ e^{iθ}) for ρ ≥ 1 (no closed form; midpoint
    rule on 8192 angles)."""
    u = np.linspace(0.0, 1.0, 513)
    th = (np.arange(8192) + 0.5) * (2 * np.pi / 8192)
    z = 1.0 - np.exp(1j * th)[None] / u[1:, None]
    h = np.concatenate([[np.pi**2 / 3.0], np.mean(np.angle(z)**2, axis=1)])
    return u, h


def circle_mean_squares(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Means over θ of ln²|1 − w| and arg²(1 − w) for ``w = ρ e^{iθ}``, ``y = ρ²`` (array).

    For ρ < 1, ``ln(1 − w) = −Σ w^k/k`` gives both as ``Li₂(ρ²)/2``; for ρ > 1,
    ``ln|1 − w| = ln ρ + ln|1 − 1/w|`` gives ``ln²ρ + Li₂(ρ⁻²)/2`` (the cross term has mean 0), and
    the phase, which then winds once round the circle, is tabulated against 1/ρ.
    """
    # Li₂(y) = spence(1 − y)
    from scipy.special import spence

    y = np.asarray(y, dtype=float)
    inside = y <= 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        li_in = 0.5 * spence(1.0 - np.where(inside, y, 0.0))
        inv = np.where(inside, 1.0, 1.0 / y)
        mag = np.where(inside, li_in, 0.25 * np.log(np.where(inside, 1.0, y))**2 + 0.5 * spence(1.0 - inv))
        u_tab, h_tab = _phase_beyond_table()
        ph = np.where(inside, li_in, np.interp(np.sqrt(inv), u_tab, h_tab))
    return mag, ph


def sigma_exact(coh: np.ndarray, dof: float) -> tuple[np.ndarray, np.ndarray]:
    """σ [dB], σ [deg] of ln|H| and of the phase of a Welch H1 (or H2) line from the exact
    distribution of the estimate, given the sample coherence γ̂² and ``dof`` = ν.

    With Gaussian noise on the output and ν + 1 independent segments, conditional on the input
    spectra, ``Ĥ − H`` is circular complex Gaussian with variance ``Ĝ_yy(1 − γ̂²)/(ν Ĝ_xx)``
    estimated from the residual power, independent of ``Ĥ`` (Goodman 1957; Bendat & Piersol,
    *Random Data*, 4th ed., ch. 9, whose confidence region (eq. 9.90)
    ``|H − Ĥ|² ≤ (2/(n − 2)) F_{2,n−2;α} (1 − γ̂²)/γ̂² Ĝ_yy/Ĝ_xx``, n = 2(ν + 1), is the exact
    form with that variance estimated; Carter, Knapp & Nuttall 1973).  Relative to the estimate,
    ``H/Ĥ = 1 − w`` with ``w = r̂ Z``, ``r̂² = (1 − γ̂²)/(ν γ̂²)`` and Z standard circular complex
    Gaussian (|Z|² ~ Exp(1), arg Z uniform).  The σ returned are the root-mean-square of
    ``ln|1 − w|`` and ``arg(1 − w)`` over Z — what the residuals of a fit and the benchmarks divide
    by σ: over arg Z in closed form (:func:`circle_mean_squares`), over |Z|² by Gauss–Legendre
    quadrature of its quantile function ``x(s) = −ln s``.

    For small r̂ this is the first-order σ (:func:`sigma_from_coherence`), ``r̂/√2``; beyond about
    1 dB it departs from it, because ln|1 − w| and arg(1 − w) are not linear in w.  Like the σ of
    the periodic and stepped-sine estimators it uses the estimated noise power as if known: the
    standardised error then follows Student's t with 2ν degrees of freedom for small errors
    (RMS ``sqrt(ν/(ν − 1))``; averaging |Z|² over F(2, 2ν) instead of Exp(1) would fold that in).
    The probability that the exact confidence disc reaches H = 0, where |H| has no lower bound and
    no σ describes the log-magnitude, is ``(1 − γ̂²)^ν`` — the line's coherence p-value
    (:func:`coherence_threshold`): lines below the threshold are such lines.  A line with γ̂² = 0
    has infinite σ.
    """
    coh = np.asarray(coh, dtype=float)
    nu = float(dof)
    if not nu > 0:
        raise IPMCError(f"dof={dof!r}: σ needs more than one average (dof > 0)")
    with np.errstate(divide="ignore", invalid="ignore"):
        r2 = np.where(coh > 0, np.clip(1.0 - coh, 0.0, None) / (nu * coh), 0.0).reshape(-1)
    x = -3.0 * np.log(_GL_T)                   # Exp(1) quantile at survival s = t³ (nodes crowd where |Z| → ∞)
    w = _GL_W * 3 * _GL_T**2
    sm, sp = np.empty(r2.size), np.empty(r2.size)
    for a in range(0, r2.size, 4096):
        mag, ph = circle_mean_squares(r2[a:a + 4096, None] * x[None])
        sm[a:a + 4096], sp[a:a + 4096] = mag @ w, ph @ w
    bad = ~(coh > 0)
    sm = np.where(bad, np.inf, np.sqrt(sm).reshape(coh.shape))
    sp = np.where(bad, np.inf, np.sqrt(sp).reshape(coh.shape))
    return NEPER_TO_DB * sm, np.degrees(sp)


def coherence_threshold(averages: float, alpha: float = COHERENCE_ALPHA, lines: int = 1) -> float:
    """Coherence that a line without any linear relation to the input exceeds with probability
    ``alpha``: ``1 − alpha^(1/(n − 1))`` for ``n`` independent averages (segments or periods);
    with ``lines`` > 1, the probability that any of that many such lines exceeds it is ``alpha``.

    Under that null the sample coherence of ``n`` averages is Beta(1, n − 1) distributed
    (Carter, Knapp & Nuttall 1973), ``P(γ̂² > x) = (1 − x)^(n − 1)``, for Welch segments and for
    whole periods of a periodic input alike.  The same number is the probability that the exact
    confidence disc of the line (:func:`sigma_exact`) reaches H = 0, where the log-magnitude has no
    lower bound.  A Welch estimate tests every bin, most of them often unexcited or buried in
    noise: at a per-line ``alpha`` it would keep about ``alpha`` × (its noise-only bins) lines whose
    response is noise, each with an error of ln|H| that no σ covers; ``lines`` makes ``alpha`` the
    false-alarm probability of the whole estimate (Šidák: ``1 − (1 − alpha)^(1/lines)`` per line).

    Parameters
    ----------
    averages : float
        Independent averages (effective segments, or whole periods); at least 2.
    alpha : float
        False-alarm probability (per line, or per estimate of ``lines`` lines), in (0, 1).
    lines : int
        Lines tested together (1: a per-line threshold).
    """
    n = float(averages)
    if not n >= 2:
        raise IPMCError(f"averages={averages!r}: a coherence needs at least 2 averages")
    if not 0 < alpha < 1:
        raise IPMCError(f"alpha={alpha!r} must lie in (0, 1)")
    if not (isinstance(lines, (int, np.integer)) and lines >= 1):
        raise IPMCError(f"lines={lines!r} must be a positive integer")
    per_line = -math.expm1(math.log1p(-alpha) / int(lines))
    return float(-math.expm1(math.log(per_line) / (n - 1.0)))


def phasor_scatter(U: np.ndarray, Y: np.ndarray, H: np.ndarray,
                   pooled: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """σ of ln|H| and of the phase [rad] from the scatter of per-period phasors, and the coherence.

    ``U`` (P, n_f) input phasors, ``Y`` (P, n_out, n_f) output phasors of P whole periods, ``H``
    (n_out, n_f) the estimate.  ``δ_p = (Y_p − H U_p)/Ȳ``: the real and imaginary parts give the
    σ of ln|H| and of the phase (sample variance with P − 1 degrees of freedom, divided by P);
    ``pooled=True`` uses ``|δ_p|²/2`` for both (2(P − 1) degrees of freedom), right when the noise
    of a line is circular (a DFT bin of stationary noise, not DC or Nyquist).  The coherence is
    ``|Σ conj(U_p) Y_p|² / (Σ|U_p|² Σ|Y_p|²)``.
    """
    P = U.shape[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        z = (Y - H[None] * U[:, None]) / Y.mean(axis=0)[None]
        if pooled:
            sl = sp = np.sqrt(np.sum(np.abs(z)**2, axis=0) / (2 * (P - 1) * P))
        else:
            sl = np.sqrt(np.sum(z.real**2, axis=0) / ((P - 1) * P))
            sp = np.sqrt(np.sum(z.imag**2, axis=0) / ((P - 1) * P))
        Suy = np.einsum("pf,pof->of", U.conj(), Y)
        coh = np.abs(Suy)**2 / (np.sum(np.abs(U)**2, axis=0)[None] * np.sum(np.abs(Y)**2, axis=0))
    sl = np.where(np.isfinite(sl), sl, np.inf)
    sp = np.where(np.isfinite(sp), sp, np.inf)
    return sl, sp, np.where(np.isfinite(coh), coh, 0.0)


def low_coherence_warning(est: FRFEstimate) -> str | None:
    """A warning when more than half of an output channel's lines fall below the per-line
    coherence threshold (``settings['coherence_threshold_per_line']`` when the estimate's threshold
    is for all its lines together, as Welch's is): an output that does not follow the input —
    noise, a wrong or unplugged channel."""
    if est.coherence is None or est.coherence_threshold is None:
        return None
    thr = float(est.settings.get("coherence_threshold_per_line", est.coherence_threshold))
    out = []
    for i, name in enumerate(est.output_names):
        low = int(np.sum(est.coherence[i] < thr))
        if low > est.frequency_hz.size / 2:
            out.append(f"{name}: {low} of {est.frequency_hz.size} lines have coherence below "
                       f"{thr:.3g} (median {np.median(est.coherence[i]):.2g})")
    if not out:
        return None
    return ("low coherence — the output barely follows the input (noise only? wrong or unplugged channel?): "
            + "; ".join(out))
