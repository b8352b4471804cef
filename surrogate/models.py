"""Fitted models: one class for a single-temperature and a temperature-scheduled rational model.

``RationalModel`` shares the interface of the physics models: ``frequency_response(frequency_hz,
temperature_c)`` and ``at(temperature_c)`` → ``control.TransferFunction`` with s in rad/s.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass

import numpy as np

from physmodel.data.files import atomic_write
from physmodel.errors import IPMCError

from . import _structure as S

__all__ = ["Scaling", "StabilityCheck", "RationalModel", "load", "SCHEMA", "SCHEMA_VERSION"]

SCHEMA = "ipmc.surrogate.rational_model"
#: 2: 'zpk' zero sections 1 + β1 s̃ + β2 s̃² (slots zb1_k, zb2_k, zb; ``structure.zero_sections``
#: says which).  1: 'zpk' zero sections s̃² + c1 s̃ + c0 (slots zc1_k, zc0_k, ze); still read, as
#: a model with ``zero_sections='monic'`` (its numbers unchanged: a polynomial schedule of one
#: kind is not one of the other).
SCHEMA_VERSION = 2
_READABLE_VERSIONS = (1, 2)


@dataclass(frozen=True)
class Scaling:
    """Scales that make the fit variables O(1).

    Parameters
    ----------
    omega_ref_rad_s : float
        Frequency scale: s̃ = s/omega_ref_rad_s. [rad/s]
    gain_ref : float
        Response scale. [output_unit/input_unit]
    temperature_center_c, temperature_scale_c : float
        Temperature scales: τ = (T − center)/scale. [°C]
    """

    omega_ref_rad_s: float
    gain_ref: float
    temperature_center_c: float = 0.0
    temperature_scale_c: float = 1.0

    def __post_init__(self):
        for name in ("omega_ref_rad_s", "gain_ref", "temperature_center_c", "temperature_scale_c"):
            v = getattr(self, name)
            if not math.isfinite(v):
                raise ValueError(f"{name} must be finite, got {v!r}")
        if self.omega_ref_rad_s <= 0 or self.gain_ref <= 0 or self.temperature_scale_c <= 0:
            raise ValueError(f"omega_ref_rad_s, gain_ref and temperature_scale_c must be > 0: {self}")


@dataclass(frozen=True)
class StabilityCheck:
    """Independent check of the poles on a dense temperature grid.

    Parameters
    ----------
    stable : bool
        Every pole in the left half-plane at every grid temperature.
    max_pole_real_part_rad_s : float
        Largest real part of any pole over the grid. [rad/s]
    worst_temperature_c : float or None
        Where it occurs (None for an unscheduled model). [°C]
    n_temperatures : int
        Grid temperatures checked.
    """

    stable: bool
    max_pole_real_part_rad_s: float
    worst_temperature_c: float | None
    n_temperatures: int


class RationalModel:
    """A (possibly temperature-scheduled) rational transfer function H(s, T).

    Parameters
    ----------
    structure : Structure
        Form, orders and polynomial degree in temperature (0: one temperature).
    params : array
        Parameter vector in the structure's layout (see ``param_names``), in the scaled
        variables of ``scaling``. [-]
    scaling : Scaling
        Frequency, gain and temperature scales.
    temperature_range_c : (float, float) or None
        Validity range; evaluating outside it raises unless ``extrapolate=True``. [°C]
    covariance : array (p, p), callable or None
        Parameter covariance from the fit, in the scaled variables; a callable returning
        it is called when the covariance is first read. [-]
    labels : dict
        ``input_name``, ``input_unit``, ``output_name``, ``output_unit``.
    info : dict
        Fit settings, status and data fingerprint, saved with the model.
    """

    def __init__(self, structure: S.Structure, params, scaling: Scaling,
                 temperature_range_c=None, covariance=None, labels=None, info=None):
        self.structure = structure
        p = np.array(params, dtype=float).ravel()
        if p.shape[0] != structure.n_params:
            raise ValueError(
                f"params has {p.shape[0]} entries, structure {structure} needs {structure.n_params}"
            )
        if not np.all(np.isfinite(p)):
            raise ValueError("params contain non-finite values")
        p.setflags(write=False)
        self._params = p
        self.scaling = scaling
        if temperature_range_c is not None:
            lo, hi = (float(v) for v in temperature_range_c)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
                raise ValueError(f"bad temperature_range_c {temperature_range_c!r}")
            temperature_range_c = (lo, hi)
        elif structure.degree > 0:
            raise ValueError("a scheduled model (degree > 0) needs temperature_range_c")
        self.temperature_range_c = temperature_range_c
        self._covariance, self._covariance_fn = None, None
        if callable(covariance):        # computed on first use (a fit's result)
            self._covariance_fn = covariance
        elif covariance is not None:
            self._covariance = self._checked_covariance(covariance)
        self.labels = dict(labels or {})
        self.info = dict(info or {})

    def _checked_covariance(self, covariance) -> np.ndarray:
        c = np.array(covariance, float)
        n = self._params.shape[0]
        if c.shape != (n, n):
            raise ValueError(f"covariance must be {n}x{n}")
        c.setflags(write=False)
        return c

    def __getstate__(self):            # pickled / deep-copied with the covariance computed
        state = self.__dict__.copy()
        state["_covariance"], state["_covariance_fn"] = self.covariance, None
        return state

    # ------------------------------------------------------------ parameters
    @property
    def covariance(self) -> np.ndarray | None:
        """Parameter covariance (read-only, in the scaled variables), or None. [-]"""
        if self._covariance_fn is not None:
            fn, self._covariance_fn = self._covariance_fn, None
            c = fn()
            self._covariance = None if c is None else self._checked_covariance(c)
        return self._covariance

    @property
    def params(self) -> np.ndarray:
        """The parameter vector (read-only), in the scaled variables. [-]"""
        return self._params

    @property
    def param_names(self) -> list[str]:
        """Names of the entries of ``params``, in order."""
        return self.structure.param_names()

    @property
    def is_scheduled(self) -> bool:
        """True when the coefficients depend on temperature (degree > 0)."""
        return self.structure.degree > 0

    @property
    def stderr(self) -> np.ndarray | None:
        """Standard errors of ``params`` from the covariance, or None without one. [-]"""
        if self.covariance is None:
            return None
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def confidence_intervals(self, level: float = 0.95):
        """Normal-approximation intervals ``(low, high)`` for ``params``, or None.

        Parameters
        ----------
        level : float
            Coverage, in (0, 1). [-]
        """
        if not 0 < level < 1:
            raise ValueError(f"level must be in (0, 1), got {level!r}")
        if self.covariance is None:
            return None
        from statistics import NormalDist

        z = NormalDist().inv_cdf(0.5 + level / 2)
        se = self.stderr
        return self._params - z * se, self._params + z * se

    def parameter_table(self) -> list[dict]:
        """One dict per parameter: name, value and, with a covariance, stderr and the 95 % interval."""
        ci = self.confidence_intervals()
        rows = []
        for i, name in enumerate(self.param_names):
            row = {"name": name, "value": float(self._params[i])}
            if ci is not None:
                row.update(stderr=float(self.stderr[i]), ci95_low=float(ci[0][i]),
                           ci95_high=float(ci[1][i]))
            rows.append(row)
        return rows

    # ------------------------------------------------------------ temperature
    def _tau(self, temperature_c, shape=(), extrapolate=False) -> np.ndarray:
        sc = self.scaling
        if temperature_c is None:
            if self.is_scheduled:
                raise ValueError("temperature_c is required for a temperature-scheduled model")
            return np.zeros(shape)
        t = np.asarray(temperature_c, float)
        if not np.all(np.isfinite(t)):
            raise ValueError(f"temperature_c must be finite, got {temperature_c!r}")
        t = np.broadcast_to(t, shape) if shape != () else t
        if self.temperature_range_c is not None and not extrapolate:
            lo, hi = self.temperature_range_c
            tol = 1e-9 * max(1.0, abs(lo), abs(hi))
            bad = (t < lo - tol) | (t > hi + tol)
            if np.any(bad):
                v = float(np.asarray(t)[bad].ravel()[0]) if np.ndim(t) else float(t)
                raise ValueError(
                    f"temperature_c={v!r} is outside the model's validity range "
                    f"[{lo}, {hi}] °C (pass extrapolate=True to evaluate anyway)"
                )
        if not self.is_scheduled:
            return np.zeros(np.shape(t))
        return (t - sc.temperature_center_c) / sc.temperature_scale_c

    # ------------------------------------------------------------ evaluation
    def frequency_response(self, frequency_hz, temperature_c=None, *, extrapolate=False):
        """Complex response at ``frequency_hz`` [Hz] and ``temperature_c`` [°C] (broadcast).

        Parameters
        ----------
        frequency_hz : array_like
            Frequencies. [Hz]
        temperature_c : float, array_like or None
            Temperatures, broadcast against ``frequency_hz``; None for an unscheduled model. [°C]
        extrapolate : bool
            Evaluate outside ``temperature_range_c`` instead of raising.
        """
        f = np.asarray(frequency_hz, float)
        if not np.all(np.isfinite(f)):
            raise ValueError("frequency_hz must be finite")
        shape = np.broadcast_shapes(f.shape, np.shape(temperature_c)) if temperature_c is not None else f.shape
        tau = self._tau(temperature_c, shape, extrapolate)
        w = np.broadcast_to(2 * np.pi * f / self.scaling.omega_ref_rad_s, shape).ravel()
        tau = np.broadcast_to(tau, shape).ravel()
        h = S.response(self.structure, self._params, w, tau)
        return (self.scaling.gain_ref * h).reshape(shape)

    #: The model kind of the model protocol (:mod:`physmodel.protocol`).
    kind = "rational"

    def response(self, frequency_hz, temperature_c=None) -> np.ndarray:
        """The model protocol (:mod:`physmodel.protocol`): the response at every temperature ×
        frequency, shape (n_T, n_f) [output/input].

        Parameters
        ----------
        frequency_hz : array_like
            Frequencies, shape (n_f,). [Hz]
        temperature_c : float, array_like or None
            Temperatures, shape (n_T,); None for an unscheduled model. [°C]
        """
        f = np.atleast_1d(np.asarray(frequency_hz, float))
        if temperature_c is None:
            return self.frequency_response(f, None)[None, :]
        t = np.atleast_1d(np.asarray(temperature_c, float))
        return self.frequency_response(f[None, :], t[:, None])

    def response_std(self, frequency_hz, temperature_c=None, *, extrapolate=False) -> np.ndarray:
        """Standard deviation of the complex response implied by the parameter covariance
        (delta method: sqrt(J Σ Jᴴ), J = ∂H/∂θ by central differences), same shape as
        ``frequency_response``. [output/input]  For a fit with weighting 'uncertainty' this is
        the noise-induced error of the model itself, e.g. at a held-out temperature.

        Parameters
        ----------
        frequency_hz : array_like
            Frequencies. [Hz]
        temperature_c : float, array_like or None
            Temperatures, broadcast against ``frequency_hz``; None for an unscheduled model. [°C]
        extrapolate : bool
            Evaluate outside ``temperature_range_c`` instead of raising.
        """
        if self.covariance is None:
            raise ValueError("this model carries no parameter covariance (e.g. a two-stage model)")
        h0 = self.frequency_response(frequency_hz, temperature_c, extrapolate=extrapolate)
        jac = np.empty(h0.shape + (self._params.size,), complex)
        for i in range(self._params.size):
            step = 1e-6 * max(1.0, abs(self._params[i]))
            hs = []
            for sign in (1.0, -1.0):
                th = self._params.copy()
                th[i] += sign * step
                m = RationalModel(self.structure, th, self.scaling, self.temperature_range_c)
                hs.append(m.frequency_response(frequency_hz, temperature_c, extrapolate=extrapolate))
            jac[..., i] = (hs[0] - hs[1]) / (2 * step)
        var = np.einsum("...i,ij,...j->...", jac, self.covariance, jac.conj()).real
        return np.sqrt(np.clip(var, 0.0, None))

    def _scalar_tau(self, temperature_c, extrapolate):
        if temperature_c is not None and np.ndim(temperature_c) != 0:
            raise ValueError("temperature_c must be a scalar here")
        return float(self._tau(temperature_c, (), extrapolate))

    def coefficients(self, temperature_c=None, *, extrapolate=False):
        """(num, den) in descending powers of s [rad/s], den monic.

        Parameters
        ----------
        temperature_c : float or None
            Temperature; None for an unscheduled model. [°C]
        extrapolate : bool
            Evaluate outside ``temperature_range_c`` instead of raising.
        """
        tau = self._scalar_tau(temperature_c, extrapolate)
        num, den = S.polynomials(self.structure, self._params, tau)
        n = self.structure.n_poles
        wr, g = self.scaling.omega_ref_rad_s, self.scaling.gain_ref
        num_s = np.array([g * c * wr ** (n - i) for i, c in enumerate(num)])
        den_s = np.array([c * wr ** (n - j) for j, c in enumerate(den)])
        return num_s[::-1], den_s[::-1]

    def at(self, temperature_c=None, *, extrapolate=False):
        """python-control ``TransferFunction`` (s in rad/s) at ``temperature_c`` [°C].

        Parameters
        ----------
        temperature_c : float or None
            Temperature; None for an unscheduled model. [°C]
        extrapolate : bool
            Evaluate outside ``temperature_range_c`` instead of raising.
        """
        import control

        num, den = self.coefficients(temperature_c, extrapolate=extrapolate)
        return control.tf(num, den)

    def zeros(self, temperature_c=None, *, extrapolate=False) -> np.ndarray:
        """Zeros at ``temperature_c`` [rad/s].

        Parameters
        ----------
        temperature_c : float or None
            Temperature; None for an unscheduled model. [°C]
        extrapolate : bool
            Evaluate outside ``temperature_range_c`` instead of raising.
        """
        tau = self._scalar_tau(temperature_c, extrapolate)
        return self.scaling.omega_ref_rad_s * S.roots(self.structure, self._params, tau)[0]

    def poles(self, temperature_c=None, *, extrapolate=False) -> np.ndarray:
        """Poles at ``temperature_c`` [rad/s].

        Parameters
        ----------
        temperature_c : float or None
            Temperature; None for an unscheduled model. [°C]
        extrapolate : bool
            Evaluate outside ``temperature_range_c`` instead of raising.
        """
        tau = self._scalar_tau(temperature_c, extrapolate)
        return self.scaling.omega_ref_rad_s * S.roots(self.structure, self._params, tau)[1]

    def max_pole_real_part(self, temperature_c=None, *, extrapolate=False) -> np.ndarray:
        """Largest pole real part at each temperature [rad/s] (shape of ``temperature_c``).
        Section denominators ('sections', 'zpk'): every section's roots in closed form,
        vectorised over the temperatures; free coefficients: eigenvalues of the stacked
        companion matrices, one batched call.

        Parameters
        ----------
        temperature_c : float, array_like or None
            Temperatures; None for an unscheduled model. [°C]
        extrapolate : bool
            Evaluate outside ``temperature_range_c`` instead of raising.
        """
        t = None if temperature_c is None else np.asarray(temperature_c, float)
        shape = () if t is None else t.shape
        taus = np.atleast_1d(self._tau(t, shape, extrapolate)).ravel()
        if self.structure.form == "coefficients":
            den = S.denominators(self.structure, self._params, taus)
            n = den.shape[1] - 1
            comp = np.zeros((taus.size, n, n))
            comp[:, 0, :] = -den[:, -2::-1] / den[:, -1:]
            comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
            re = np.linalg.eigvals(comp).real.max(axis=1)
        else:
            re = S.section_max_real_part(self.structure, self._params, taus)
        return (re * self.scaling.omega_ref_rad_s).reshape(shape)

    def stability_check(self, n_temperatures: int = 501) -> StabilityCheck:
        """Largest pole real part over a dense grid of the validity range.

        Parameters
        ----------
        n_temperatures : int
            Grid points over ``temperature_range_c`` (scheduled models).
        """
        if self.is_scheduled:
            lo, hi = self.temperature_range_c
            grid = np.linspace(lo, hi, int(n_temperatures))
            re = self.max_pole_real_part(grid)
        else:
            grid, re = [None], np.atleast_1d(self.max_pole_real_part())
        i = int(np.argmax(re))
        worst = float(re[i])
        return StabilityCheck(bool(worst < 0), worst, None if grid[i] is None else float(grid[i]),
                              len(grid))

    # ------------------------------------------------------------ persistence
    def to_dict(self) -> dict:
        """The model as JSON-ready data (schema ``ipmc.surrogate.rational_model``, versioned)."""
        def clean(x):
            return None if x is None else np.asarray(x, float).tolist()

        return {
            "schema": SCHEMA,
            "schema_version": SCHEMA_VERSION,
            "structure": self.structure.to_dict(),
            "scaling": asdict(self.scaling),
            "temperature_range_c": None if self.temperature_range_c is None else list(self.temperature_range_c),
            "params": {"names": self.param_names, "values": clean(self._params),
                       "covariance": clean(self.covariance)},
            "labels": self.labels,
            "info": self.info,
            "conventions": {"s": "rad/s", "frequency_edges": "Hz", "temperature": "degC",
                            "model": "H = gain_ref*N(s/omega_ref, tau)/D(s/omega_ref, tau), "
                                     "tau = (T - temperature_center_c)/temperature_scale_c"},
        }

    def to_json(self, path) -> None:
        """Write the model as versioned JSON (atomically).

        Parameters
        ----------
        path : str or Path
            The file to write.
        """
        text = json.dumps(self.to_dict(), indent=2, allow_nan=False)
        atomic_write(path, lambda fh: fh.write(text))

    @classmethod
    def from_dict(cls, d: dict) -> RationalModel:
        """The model from :meth:`to_dict` data; a wrong schema or version, or parameter names that
        do not match the structure, raise ``ValueError`` naming them.

        Parameters
        ----------
        d : dict
            The data.
        """
        if not isinstance(d, dict) or d.get("schema") != SCHEMA:
            raise IPMCError(f"not a {SCHEMA} document (schema={d.get('schema') if isinstance(d, dict) else None!r})")
        version = d.get("schema_version")
        if isinstance(version, bool) or version not in _READABLE_VERSIONS:
            raise IPMCError(f"unsupported schema_version {version!r}; this code reads "
                            f"{', '.join(map(str, _READABLE_VERSIONS))}")
        for key, kind in (("structure", dict), ("params", dict), ("scaling", dict)):
            if not isinstance(d.get(key), kind):
                raise IPMCError(f"key {key!r}: expected an object, got {type(d.get(key)).__name__}")
        structure = dict(d["structure"])
        if version == 1:
            if "zero_sections" in structure:
                raise IPMCError("key 'structure.zero_sections': not part of schema_version 1")
            if structure.get("form") == "zpk":
                structure["zero_sections"] = "monic"
        params = d["params"]
        for key in ("names", "values"):
            if not isinstance(params.get(key), list):
                raise IPMCError(f"key 'params.{key}': expected a list, got {type(params.get(key)).__name__}")
        try:
            st = S.Structure(**structure)
            scaling = Scaling(**d["scaling"])
        except (TypeError, ValueError) as exc:
            raise IPMCError(f"key 'structure' or 'scaling': {exc}") from None
        if params["names"] != st.param_names():
            raise IPMCError("key 'params.names': the parameter names do not match the structure "
                            f"(expected {st.param_names()})")
        values = np.asarray(params["values"], dtype=object)
        if values.shape != (len(params["names"]),) or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in values):
            raise IPMCError(f"key 'params.values': expected {len(params['names'])} finite numbers")
        return cls(st, params["values"], scaling, d.get("temperature_range_c"), params.get("covariance"),
                   d.get("labels"), d.get("info"))

    def __repr__(self):
        st = self.structure
        rng = "" if self.temperature_range_c is None else f", T in {list(self.temperature_range_c)} °C"
        return (f"RationalModel(form={st.form!r}, n_zeros={st.n_zeros}, n_poles={st.n_poles}, "
                f"degree={st.degree}{rng})")


def load(path) -> RationalModel:
    """Read a model written by ``RationalModel.to_json``.

    Parameters
    ----------
    path : str or Path
        The JSON file.
    """
    from physmodel.data.files import read_text

    try:
        d = json.loads(read_text(path))
    except json.JSONDecodeError as exc:
        raise IPMCError(f"{path}: not valid JSON ({exc})") from None
    try:
        return RationalModel.from_dict(d)
    except IPMCError as exc:
        raise IPMCError(f"{path}: {exc}") from None
