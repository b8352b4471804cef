"""Records of the least-squares engine (:mod:`physmodel.estimation.lsq`): what is free
(:class:`FreeParameter`), how a start went (:class:`StartRecord`) and the outcome (:class:`CalibrationResult`; what holding cost:
:class:`~physmodel.estimation.identifiability.HoldRecord`; what the data determine:
:class:`~physmodel.estimation.identifiability.Identifiability`).  The engine's array helpers are in
:mod:`physmodel.estimation.batching`.  Physical units throughout.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..data.files import atomic_write
from ..errors import IPMCError, ParameterError
from ..params import IPMCParameters

if TYPE_CHECKING:
    from .identifiability import HoldRecord

Values = Mapping[str, float]

# =============================================================================== free parameters
@dataclass(frozen=True)
class FreeParameter:
    """A parameter to calibrate, with bounds in its physical unit.

    Parameters
    ----------
    name : str
        An :class:`~physmodel.IPMCParameters` field, ``"omega_n"`` or
        ``"laws.<quantity>.<attribute>"`` (a temperature-law parameter).
    lower, upper : float
        Bounds, ``lower < upper``. [the parameter's SI unit]
    scale : {"log", "linear"} or None
        ``"log"`` fits log10 |x| (both bounds of one sign, not zero); default ``"log"`` when
        ``lower > 0`` else ``"linear"``.
    initial : float or None
        Start value within the bounds; default the base value in :func:`~physmodel.calibrate`,
        else the geometric (log) or arithmetic (linear) mid-point. [the parameter's SI unit]
    """

    name: str
    lower: float
    upper: float
    scale: str | None = None
    initial: float | None = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ParameterError(f"a free parameter needs a non-empty name, got {self.name!r}")
        for k in ("lower", "upper"):
            v = getattr(self, k)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v):
                raise ParameterError(f"free parameter {self.name}: {k}={v!r} must be a finite number")
            object.__setattr__(self, k, float(v))
        if not self.lower < self.upper:
            raise ParameterError(f"free parameter {self.name}: bounds reversed or empty, lower={self.lower!r} "
                                 f"must be < upper={self.upper!r}")
        scale = self.scale or ("log" if self.lower > 0 else "linear")
        if scale not in ("log", "linear"):
            raise ParameterError(f"free parameter {self.name}: scale={self.scale!r}; expected 'log' or 'linear'")
        if scale == "log" and not (self.lower > 0 or self.upper < 0):
            raise ParameterError(f"free parameter {self.name}: a log scale needs bounds of one sign, not "
                                 f"crossing zero; got [{self.lower!r}, {self.upper!r}]")
        object.__setattr__(self, "scale", scale)
        if self.initial is not None:
            v = self.initial
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v):
                raise ParameterError(f"free parameter {self.name}: initial={v!r} must be a finite number")
            if not self.lower <= v <= self.upper:
                raise ParameterError(f"free parameter {self.name}: initial={v!r} lies outside its bounds "
                                     f"[{self.lower!r}, {self.upper!r}]")
            object.__setattr__(self, "initial", float(v))

    # scaled coordinate ---------------------------------------------------------------------
    @property
    def sign(self) -> float:
        """-1 for a log-scaled parameter with negative bounds, else +1. [-]"""
        return -1.0 if self.upper < 0 else 1.0

    def to_z(self, x):
        """The fitted coordinate of physical values: log10 |x| (log scale) or the position in the
        bounds, 0 to 1 (linear scale).

        Parameters
        ----------
        x : float or array_like
            Values. [the parameter's SI unit]

        Returns
        -------
        ndarray
            The coordinate z. [-]
        """
        x = np.asarray(x, dtype=float)
        if self.scale == "log":
            return np.log10(np.abs(x))
        return (x - self.lower) / (self.upper - self.lower)

    def from_z(self, z):
        """Physical values of the fitted coordinate (the inverse of :meth:`to_z`).

        Parameters
        ----------
        z : float or array_like
            Coordinate; log-scale exponents are clipped to ±300 so that the interval of an
            undetermined parameter stays finite. [-]

        Returns
        -------
        ndarray
            Values. [the parameter's SI unit]
        """
        z = np.asarray(z, dtype=float)
        if self.scale == "log":
            # clipped so that the interval of an undetermined parameter (huge se(z)) stays finite
            return self.sign * 10.0 ** np.clip(z, -300.0, 300.0)
        return self.lower + z * (self.upper - self.lower)

    @property
    def z_bounds(self) -> tuple[float, float]:
        """The bounds in the fitted coordinate, (low, high). [-]"""
        a, b = float(self.to_z(self.lower)), float(self.to_z(self.upper))
        return (min(a, b), max(a, b))

    def midpoint(self) -> float:
        """Geometric (log) or arithmetic (linear) mid-point of the bounds."""
        lo, hi = self.z_bounds
        return float(self.from_z(0.5 * (lo + hi)))

    def with_initial(self, value: float) -> FreeParameter:
        """A copy starting at ``value``.

        Parameters
        ----------
        value : float
            Start value within the bounds. [the parameter's SI unit]
        """
        return replace(self, initial=float(value))


def lhs_starts(free: Sequence[FreeParameter], n: int, seed: int) -> np.ndarray:
    """``n`` Latin-hypercube points in the scaled boxes (n, n_free), seeded."""
    from scipy.stats import qmc

    if n <= 0:
        return np.empty((0, len(free)))
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError(f"seed must be a non-negative integer, got {seed!r}")
    u = qmc.LatinHypercube(d=len(free), seed=seed).random(n)
    lo = np.array([fp.z_bounds[0] for fp in free])
    hi = np.array([fp.z_bounds[1] for fp in free])
    return lo + u * (hi - lo)




# =============================================================================== results
@dataclass(frozen=True)
class StartRecord:
    """One start of the multi-start search: where it began and where it ended."""

    index: int
    initial: dict
    final: dict
    cost: float
    nfev: int
    status: int
    message: str
    joined: int | None = None       # status -2: the earlier start whose optimum it reached


@dataclass
class CalibrationResult:
    """Outcome of a calibration.  Physical units throughout; intervals are 95 %.

    Parameters
    ----------
    names : list of str
        The free parameters, in fit order.
    values : dict
        Fitted (or held) value of every free parameter. [each parameter's SI unit]
    parameters : IPMCParameters or None
        The base set with the determined values (held ones at their base value).
    stderr : dict
        Standard error (delta method for log parameters; NaN when held). [each parameter's SI unit]
    ci_lower, ci_upper : dict
        95 % interval (NaN when held). [each parameter's SI unit]
    correlation : ndarray
        (n, n) correlation in the order of ``names`` (NaN rows for held ones). [-]
    cost : float
        ½ Σ r² of the weighted residuals at the optimum. [-]
    expected_cost : float
        What the noise alone explains, F − nθ/2 (F residual terms, nθ fitted parameters). [-]
    cost_std : float
        Its standard deviation, sqrt(F − nθ/2); a cost many of these above ``expected_cost``
        means the model does not fit the data. [-]
    n_lines : int
        Frequency lines in the data.
    n_evaluations, n_model_calls : int
        Model evaluations (parameter sets) and the vectorised calls that made them.
    converged : bool
        Whether the best start converged.
    message : str
        The optimiser's message for the best start.
    starts : list of StartRecord
        Every start: where it began, where it ended.
    identifiability : dict
        {name: :class:`~physmodel.estimation.identifiability.Identifiability`}: whether the data determine the parameter, and why not.
    noise_estimated : bool
        True when the data had no per-line σ and the noise level was estimated from the residuals.
    noise_scale : float
        The estimated noise scale (1 when the sweep's σ were used). [-]
    held : list of str
        Undetermined parameters kept at their start value.
    free : list of FreeParameter
        The free parameters as fitted (bounds, scale).
    band_hz : tuple of float
        (lowest, highest) frequency of the data. [Hz]
    temperatures_c : list of float
        Temperatures of the data. [°C]
    elapsed_s : float
        Wall time of the calibration. [s]
    metadata : dict
        Provenance (data source, base set, settings).
    goodness_of_fit : GoodnessOfFit or None
        The χ² test of the final cost (:func:`~physmodel.estimation.residuals.goodness_of_fit`).
    holds : list of HoldRecord
        (:class:`~physmodel.estimation.identifiability.HoldRecord`) Every hold step tried, with the cost before (all free) and after; the last one refused
        (if any) was undone: its ``added`` parameters keep their fitted value (often at a bound)
        without being determined (:attr:`hold_refused`).
    """

    names: list
    values: dict
    parameters: IPMCParameters | None
    stderr: dict
    ci_lower: dict
    ci_upper: dict
    correlation: np.ndarray
    cost: float
    expected_cost: float
    cost_std: float
    n_lines: int
    n_evaluations: int
    n_model_calls: int
    converged: bool
    message: str
    starts: list
    identifiability: dict
    noise_estimated: bool
    noise_scale: float
    held: list
    free: list
    band_hz: tuple
    temperatures_c: list
    elapsed_s: float
    metadata: dict = field(default_factory=dict)
    goodness_of_fit: object = None    # physmodel.estimation.residuals.GoodnessOfFit
    holds: list = field(default_factory=list)

    @property
    def hold(self) -> HoldRecord | None:
        """The last hold step (the one that decided), or None when nothing was held."""
        return self.holds[-1] if self.holds else None

    @property
    def hold_refused(self) -> list:
        """Undetermined parameters left free because holding them would worsen the fit beyond the
        test (their value is the fit's, often at a bound; their interval is not a valid 95 % one)."""
        from .identifiability import refused_names

        return refused_names(self.holds, self.held)

    def hold_line(self) -> str:
        """One sentence on the hold: what it cost and whether it was taken ("" when none)."""
        return "" if self.hold is None else self.hold.line()

    @property
    def adequate(self) -> bool:
        """The model fits the data (goodness-of-fit test passed, or not available)."""
        return self.goodness_of_fit is None or bool(self.goodness_of_fit.adequate)

    @property
    def determined(self) -> list:
        """The free parameters the data determine (``names`` without ``held`` and ``hold_refused``)."""
        return [n for n in self.names if n not in self.held and n not in self.hold_refused]

    def summary(self) -> str:
        """A plain-text report: convergence, data, cost against its expectation, and each
        parameter with its 95 % interval or the reason it was held."""
        lines = [
            f"calibration: {'converged' if self.converged else 'NOT CONVERGED'} ({self.message})",
            f"  data: {self.n_lines} lines, {len(self.temperatures_c)} temperature(s), band "
            f"{self.band_hz[0]:.4g}-{self.band_hz[1]:.4g} Hz; noise "
            + ("estimated from the residuals (no per-line std in the data), scale "
               f"{self.noise_scale:.3g}" if self.noise_estimated else "from the sweep's per-line std"),
            f"  cost {self.cost:.4g} (expected {self.expected_cost:.4g} ± {self.cost_std:.3g}); "
            f"{len(self.starts)} start(s); {self.n_evaluations} model evaluations in {self.n_model_calls} calls; "
            f"{self.elapsed_s:.2f} s",
            *([f"  goodness of fit: {'adequate' if self.adequate else 'INADEQUATE'} — {self.goodness_of_fit.reason}"]
              if self.goodness_of_fit is not None else []),
            *([f"  hold: {self.hold_line()}"] if self.holds else []),
            f"  {'parameter':34s} {'value':>12s} {'95 % interval':>27s}  status",
        ]
        for n in self.names:
            ident = self.identifiability.get(n)
            if n in self.held:
                lines.append(f"  {n:34s} {self.values[n]:12.5g} {'(held)':>27s}  UNDETERMINED: {ident.reason}")
            else:
                ci = f"[{self.ci_lower[n]:.5g}, {self.ci_upper[n]:.5g}]"
                ok = n not in self.identifiability or self.identifiability[n].identifiable
                if n in self.hold_refused:
                    lines.append(f"  {n:34s} {self.values[n]:12.5g} {ci + ' (not valid)':>27s}  "
                                 f"NOT DETERMINED (hold refused): {ident.reason}")
                    continue
                lines.append(f"  {n:34s} {self.values[n]:12.5g} {ci:>27s}  {'ok' if ok else 'NOT ASSESSED (model inadequate)'}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """The record as JSON-ready data (format ``ipmc-calibration`` 1; non-finite numbers as
        None)."""
        def num(v):
            v = float(v)
            return v if math.isfinite(v) else None

        corr = [[num(c) for c in row] for row in np.asarray(self.correlation, dtype=float)]
        return {
            "format": "ipmc-calibration", "version": 1,
            "converged": bool(self.converged), "message": self.message,
            "parameters": [
                {"name": n, "value": num(self.values[n]), "stderr": num(self.stderr[n]),
                 "ci95_lower": num(self.ci_lower[n]), "ci95_upper": num(self.ci_upper[n]),
                 "held": n in self.held, "hold_refused": n in self.hold_refused,
                 "identifiable": bool(self.identifiability[n].identifiable) if n in self.identifiability else None,
                 "reason": self.identifiability[n].reason if n in self.identifiability else "",
                 "sensitivity_peak_hz": (num(self.identifiability[n].sensitivity_peak_hz)
                                         if n in self.identifiability and self.identifiability[n].sensitivity_peak_hz is not None else None),
                 "bounds": [fp.lower, fp.upper], "scale": fp.scale}
                for n, fp in zip(self.names, self.free)
            ],
            "correlation": {"names": list(self.names), "matrix": corr},
            "cost": num(self.cost), "expected_cost": num(self.expected_cost), "cost_std": num(self.cost_std),
            "n_lines": int(self.n_lines), "n_evaluations": int(self.n_evaluations),
            "n_model_calls": int(self.n_model_calls),
            "noise_estimated": bool(self.noise_estimated), "noise_scale": num(self.noise_scale),
            "band_hz": [float(self.band_hz[0]), float(self.band_hz[1])],
            "temperatures_c": [float(t) for t in self.temperatures_c],
            "starts": [{"index": s.index, "initial": s.initial, "final": s.final, "cost": num(s.cost),
                        "nfev": s.nfev, "status": s.status, "message": s.message} for s in self.starts],
            "elapsed_s": float(self.elapsed_s),
            "goodness_of_fit": self.goodness_of_fit.to_dict() if self.goodness_of_fit is not None else None,
            "holds": [h.to_dict() for h in self.holds],
            "metadata": {k: str(v) for k, v in self.metadata.items()},
        }

    def estimates(self) -> list:
        """The fitted parameters as records: name, value, ci95 [lower, upper], status. [SI]"""
        def num(v):
            v = float(v)
            return v if math.isfinite(v) else None

        out = []
        for n in self.names:
            held = n in self.held
            status = "held at base (undetermined)" if held else "hold refused (at its bound, not determined)" if (
                n in self.hold_refused) else (
                "determined" if n not in self.identifiability or self.identifiability[n].identifiable
                else "not assessed")
            out.append({"name": n, "value": num(self.values[n]), "ci95": [num(self.ci_lower[n]), num(self.ci_upper[n])],
                        "status": status})
        return out

    def to_model_file(self, provenance=None, *, diagnosis: str | None = None, named=(), effects=None):
        """The :class:`physmodel.ModelFile` of this result: the calibrated parameters, the effects
        held or fitted in the model, this fit's goodness-of-fit verdict and ``provenance``.

        Parameters
        ----------
        provenance : physmodel.model_file.Provenance or None
            Where the data came from (the caller knows the file and the command).
        diagnosis : str or None
            The verdict of a diagnosis that chose this fit.
        named : sequence of str
            Effects the diagnosis named.
        effects : dict or None
            Effects in the model ``{name: {parameter: value}}`` (SI); default those of the
            metadata (``calibrate(effects=...)``) with any fitted ``effect.parameter`` values.
        """
        from ..model_file import FitVerdict, ModelFile, Provenance
        from ..parameter_paths import is_effect_parameter

        if self.parameters is None:
            raise IPMCError("this calibration produced no parameter set; there is no model to write")
        eff = {k: dict(v) for k, v in (effects if effects is not None else self.metadata.get("effects") or {}).items()}
        for n in self.names:
            if is_effect_parameter(n):
                e, p = n.split(".", 1)
                eff.setdefault(e, {})[p] = float(self.values[n])
        verdict = None if self.goodness_of_fit is None else FitVerdict.from_goodness(
            self.goodness_of_fit, diagnosis, named)
        if not self.converged:
            verdict = FitVerdict(False, None if verdict is None else verdict.chi2, None if verdict is None else verdict.dof,
                                 None if verdict is None else verdict.p_value,
                                 f"the fit did not converge ({self.message}): its parameters are not an estimate",
                                 diagnosis, tuple(named))
        if provenance is None:
            provenance = Provenance("physmodel.calibrate", data_fingerprint=self.metadata.get("data_fingerprint"),
                                    temperatures_c=tuple(self.temperatures_c), band_hz=tuple(self.band_hz))
        return ModelFile(self.metadata.get("kind", "actuator"), self.parameters, eff, self.metadata.get("quantity"),
                         self.metadata.get("kernel", "boundary_charge"), verdict, tuple(self.estimates()), provenance)

    def save(self, path) -> Path:
        """Atomic JSON: a parameter-set payload (readable by :func:`physmodel.load_parameter_set`)
        when ``parameters`` is known, plus the calibration record under ``"calibration"``.

        Parameters
        ----------
        path : str or Path
            The JSON file to write.

        Returns
        -------
        Path
            The file written.
        """
        from ..formats import PARAMETER_SET_FORMAT, PARAMETER_SET_VERSION, finite_json

        payload: dict = {}
        if self.parameters is not None:
            payload = {"format": PARAMETER_SET_FORMAT, "version": PARAMETER_SET_VERSION,
                       "parameters": finite_json(self.parameters.to_dict())}
        payload["calibration"] = self.to_dict()
        text = json.dumps(payload, indent=2, allow_nan=False)
        return atomic_write(Path(path), lambda fh: fh.write(text + "\n"))
