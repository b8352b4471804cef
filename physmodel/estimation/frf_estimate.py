"""The result every FRF estimator returns (:class:`FRFEstimate`) and what the estimators share:
checks of the input and output samples, the σ of a line from its coherence (Welch) or from the
scatter of per-period phasors (periodic excitation, stepped sine), and the coherence a line needs to
stand out of noise.  The estimators are :mod:`physmodel.estimation.frf` (Welch, and the front door
that reads the excitation), :mod:`physmodel.estimation.periodic` and
:mod:`physmodel.estimation.stepped`; their statistics are described in
:mod:`physmodel.estimation.frf`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

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
        by the estimators from their number of averages; see :func:`coherence_threshold`)."""
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
    """σ [dB], σ [deg] of an FRF line from coherence and degrees of freedom (Bendat & Piersol 9.90)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.sqrt(np.clip(1.0 - coh, 0.0, None) / (2.0 * dof * coh))
    s = np.where(coh > 0, s, np.inf)
    return NEPER_TO_DB * s, np.degrees(s)




def coherence_threshold(averages: float, alpha: float = COHERENCE_ALPHA) -> float:
    """Coherence that a line without any linear relation to the input exceeds with probability
    ``alpha``: ``1 − alpha^(1/(n − 1))`` for ``n`` independent averages (segments or periods).

    Under that null the sample coherence of ``n`` averages is Beta(1, n − 1) distributed
    (Carter, Knapp & Nuttall 1973), ``P(γ̂² > x) = (1 − x)^(n − 1)``, for Welch segments and for
    whole periods of a periodic input alike.

    Parameters
    ----------
    averages : float
        Independent averages (effective segments, or whole periods); at least 2.
    alpha : float
        False-alarm probability per line, in (0, 1).
    """
    n = float(averages)
    if not n >= 2:
        raise IPMCError(f"averages={averages!r}: a coherence needs at least 2 averages")
    if not 0 < alpha < 1:
        raise IPMCError(f"alpha={alpha!r} must lie in (0, 1)")
    return float(1.0 - alpha ** (1.0 / (n - 1.0)))


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
    """A warning when more than half of an output channel's lines fall below the coherence
    threshold (an output that does not follow the input: noise, a wrong or unplugged channel)."""
    if est.coherence is None or est.coherence_threshold is None:
        return None
    out = []
    for i, name in enumerate(est.output_names):
        low = int(np.sum(est.coherence[i] < est.coherence_threshold))
        if low > est.frequency_hz.size / 2:
            out.append(f"{name}: {low} of {est.frequency_hz.size} lines have coherence below "
                       f"{est.coherence_threshold:.3g} (median {np.median(est.coherence[i]):.2g})")
    if not out:
        return None
    return ("low coherence — the output barely follows the input (noise only? wrong or unplugged channel?): "
            + "; ".join(out))
