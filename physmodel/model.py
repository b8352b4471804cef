"""Shared machinery of the physical models: chunked vectorised evaluation and result records.

A model kernel maps a dict of broadcastable parameter arrays (one value per evaluation point)
and the Laplace variable ``s`` to a dict of complex arrays.  :func:`evaluate_grid` lays the
points of (parameter sets × temperatures × s) out flat and evaluates them in chunks, so that
temporaries stay bounded (about 40 complex arrays of ``chunk_size``) whatever the grid size;
the output may be a preallocated array (e.g. a ``numpy.memmap``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .errors import IPMCError
from .params import STATE_FIELDS, IPMCParameters, ParameterTable, State, as_parameter_list

#: Default number of points per chunk (keeps temporaries in L2/L3 cache).
DEFAULT_CHUNK = 16384

Kernel = Callable[[Mapping[str, np.ndarray], np.ndarray, Sequence[str]], dict]


def real_array(values, name: str, unit: str) -> np.ndarray:
    """``values`` as a float array; complex, boolean or non-numeric input is an IPMCError naming
    ``name`` (numpy would silently drop an imaginary part)."""
    a = np.asarray(values)
    if a.dtype.kind not in "iuf":
        what = "complex" if a.dtype.kind == "c" else ("boolean" if a.dtype.kind == "b" else f"{a.dtype}")
        raise IPMCError(f"{name} must be real numbers [{unit}], got {what} values {a.reshape(-1)[:3].tolist()}")
    return a.astype(float)


def check_finite_output(values: Mapping[str, np.ndarray], f_hz: np.ndarray, T_c: np.ndarray) -> None:
    """An IPMCError naming the frequencies and temperatures where a quantity is not finite (the
    model overflows double precision far outside 1e-9–1e12 Hz), instead of NaN with a warning."""
    for q, v in values.items():
        bad = ~np.isfinite(v)
        if bad.any():
            _, it, jf = np.nonzero(bad)
            raise IPMCError(f"{q} is not finite in double precision at frequency_hz {np.unique(f_hz[jf])[:3].tolist()} "
                            f"and temperature_c {np.unique(T_c[it])[:3].tolist()}; the model is evaluated "
                            "reliably over 1e-9–1e12 Hz")


def check_frequencies(frequency_hz) -> np.ndarray:
    """Validate a 1-D array of strictly positive, finite, real frequencies [Hz]."""
    f = np.atleast_1d(real_array(frequency_hz, "frequency_hz", "Hz"))
    if f.ndim != 1:
        raise IPMCError(f"frequency_hz must be 1-D, got shape {f.shape}")
    if f.size == 0:
        raise IPMCError("frequency_hz is empty; expected at least one frequency [Hz]")
    bad = ~np.isfinite(f) | (f <= 0)
    if np.any(bad):
        raise IPMCError(
            f"frequencies must be finite and > 0 Hz (use dc_gain() for 0 Hz); got {f[bad][:5].tolist()}"
        )
    return f


def check_s(s) -> np.ndarray:
    s = np.atleast_1d(np.asarray(s, dtype=complex))
    if s.ndim != 1:
        raise IPMCError(f"s must be 1-D, got shape {s.shape}")
    if not np.all(np.isfinite(s)):
        raise IPMCError(f"s must be finite, got {s[~np.isfinite(s)][:5].tolist()}")
    if np.any(s == 0):
        raise IPMCError("s = 0 is a singular point of the impedance; use dc_gain() for DC values")
    return s


def evaluate_grid(state: State, s: np.ndarray, kernel: Kernel, quantities: Sequence[str],
                  chunk_size: int = DEFAULT_CHUNK, out: Mapping[str, np.ndarray] | None = None,
                  progress: Callable[[int], None] | None = None) -> dict[str, np.ndarray]:
    """Evaluate ``kernel`` on every (set, temperature, s) point; returns arrays (n_sets, n_T, n_s).

    ``s``: the points (n_s,), or one row of points per parameter set (n_sets, 1, n_s) — a kernel
    effect whose ŝ differs between the sets of a batch (each row evaluated on its own set's points,
    the same operations as a call per set)."""
    if chunk_size < 1:
        raise IPMCError(f"chunk_size must be >= 1, got {chunk_size}")
    n_sets, n_T = state.T.shape[:2]
    s = np.asarray(s)
    per_set = s.ndim == 3
    if per_set and s.shape[:2] != (n_sets, 1):
        raise IPMCError(f"per-set points must have shape ({n_sets}, 1, n_s), got {s.shape}")
    n_s = s.shape[-1]
    n_rows = n_sets * n_T
    # the points of each row (n_rows, n_s), set-major, or one row for all (1, n_s)
    pts = np.repeat(s[:, 0, :], n_T, axis=0) if per_set else s[None, :]
    flat_state = {k: np.ascontiguousarray(getattr(state, k).reshape(n_rows)) for k in STATE_FIELDS}
    results: dict[str, np.ndarray] = {}
    for q in quantities:
        if out is not None and q in out:
            arr = out[q]
            if arr.shape != (n_sets, n_T, n_s) or arr.dtype != np.complex128:
                raise IPMCError(f"out[{q!r}] must be complex128 with shape {(n_sets, n_T, n_s)}, "
                                f"got {arr.dtype} {arr.shape}")
            results[q] = arr
        else:
            results[q] = np.empty((n_sets, n_T, n_s), dtype=complex)
    rows_out = {q: results[q].reshape(n_rows, n_s) for q in quantities}
    if n_s >= chunk_size:
        # long rows: scalar parameters, chunks along s
        for r in range(n_rows):
            params = {k: v[r] for k, v in flat_state.items()}
            for start in range(0, n_s, chunk_size):
                stop = min(start + chunk_size, n_s)
                vals = kernel(params, pts[r if per_set else 0, start:stop], quantities)
                for q in quantities:
                    rows_out[q][r, start:stop] = vals[q]
                if progress:
                    progress(stop - start)
        return results
    # short rows: blocks of whole rows, parameters broadcast as columns
    rows_per_block = max(1, chunk_size // n_s)
    for r0 in range(0, n_rows, rows_per_block):
        r1 = min(r0 + rows_per_block, n_rows)
        params = {k: v[r0:r1, None] for k, v in flat_state.items()}
        vals = kernel(params, pts[r0:r1] if per_set else pts, quantities)
        for q in quantities:
            rows_out[q][r0:r1] = vals[q]
        if progress:
            progress((r1 - r0) * n_s)
    return results


@dataclass(frozen=True)
class FrequencyResponse:
    """Complex frequency responses on a grid (parameter sets × temperatures × frequencies).

    Attributes
    ----------
    frequency_hz : (n_f,) ndarray          frequencies [Hz]
    temperature_c : (n_T,) ndarray         temperatures [°C]
    parameter_sets : tuple of str          names of the parameter sets (first axis)
    values : dict[str, ndarray]            complex arrays (n_sets, n_T, n_f), SI units in ``units``
    units : dict[str, str]                 unit of each quantity (output/input)
    descriptions : dict[str, str]          what each quantity is
    """

    frequency_hz: np.ndarray
    temperature_c: np.ndarray
    parameter_sets: tuple
    values: dict
    units: dict
    descriptions: dict = field(default_factory=dict)

    @property
    def omega(self) -> np.ndarray:
        """Angular frequencies [rad/s]."""
        return 2 * np.pi * self.frequency_hz

    def __getitem__(self, quantity: str) -> np.ndarray:
        try:
            return self.values[quantity]
        except KeyError:
            raise KeyError(f"no quantity {quantity!r}; available: {sorted(self.values)}") from None

    def magnitude_db(self, quantity: str, scale: float = 1.0) -> np.ndarray:
        """20 log10(|value|·scale) [dB]; ``scale`` converts units (1e3 for m→mm)."""
        return 20 * np.log10(np.abs(self[quantity]) * scale)

    def phase_deg(self, quantity: str) -> np.ndarray:
        """Phase unwrapped along frequency [deg]."""
        return np.degrees(np.unwrap(np.angle(self[quantity]), axis=-1))


class PhysicsModel:
    """Base class: a parameter set (or batch) evaluated through a kernel."""

    quantities: tuple = ()
    units: dict = {}
    descriptions: dict = {}

    def __init__(self, params: IPMCParameters | Sequence[IPMCParameters], chunk_size: int = DEFAULT_CHUNK):
        self.params = params
        if int(chunk_size) < 1:
            raise IPMCError(f"chunk_size must be >= 1, got {chunk_size}")
        self.chunk_size = int(chunk_size)

    @property
    def params(self) -> list[IPMCParameters]:
        """The parameter sets (first axis of every result).  Assign a new list to change them: the
        sets' arrays and names are built on assignment, so editing the list in place is not seen."""
        return self._params

    @params.setter
    def params(self, params: IPMCParameters | Sequence[IPMCParameters]) -> None:
        # the sets' numbers as arrays and their names, once per batch (not per evaluation)
        self._params = as_parameter_list(params)
        self._table = ParameterTable.of(self._params)
        self._names = tuple(p.name for p in self._params)

    # subclasses provide _kernel(params, s, quantities) -> dict
    def _kernel(self, p, s, quantities):  # pragma: no cover - abstract
        raise NotImplementedError

    def _check_quantities(self, quantities: Iterable[str]) -> tuple:
        qs = tuple(quantities)
        bad = [q for q in qs if q not in self.quantities]
        if bad or not qs:
            raise IPMCError(f"unknown quantity {bad or qs}; {type(self).__name__} provides {self.quantities}")
        return qs

    def state(self, temperature_c) -> State:
        return self._table.state(temperature_c)

    def evaluate_state(self, state: State, s, quantities=None) -> dict[str, np.ndarray]:
        """Quantities at complex Laplace points for a state built by the caller (e.g. by a
        :class:`~physmodel.parameter_paths.StateMap`, one row per parameter set), whatever this
        model's own parameter sets.  Nothing is checked but the quantity names: the fast path of
        calibration, which validates its points once.

        Parameters
        ----------
        state : State
            Parameter values as arrays (n_rows, n_T, 1) (see :class:`~physmodel.params.State`). [SI]
        s : array_like
            1-D complex Laplace points, nonzero and finite (not checked). [1/s]
        quantities : sequence of str or None
            Names from :attr:`quantities` (default all).

        Returns
        -------
        dict of str to ndarray
            Complex arrays (n_rows, n_T, n_s) in the units of :attr:`units`.
        """
        qs = self._check_quantities(quantities or self.quantities)
        return evaluate_grid(state, np.asarray(s), self._kernel, qs, self.chunk_size)

    def evaluate(self, s, temperature_c, quantities=None, out=None, progress=None) -> dict:
        """Quantities at complex Laplace points ``s`` [1/s]; arrays (n_sets, n_T, n_s)."""
        qs = self._check_quantities(quantities or self.quantities)
        s = check_s(s)
        return evaluate_grid(self.state(temperature_c), s, self._kernel, qs, self.chunk_size, out, progress)

    #: The model kind (see :mod:`physmodel.protocol`); set by each subclass.
    kind: str = ""
    #: The primary quantity returned by :meth:`response`.
    primary_quantity: str = ""

    def response(self, frequency_hz, temperature_c) -> np.ndarray:
        """The primary quantity (:attr:`primary_quantity`) of the first parameter set, shape
        (n_T, n_f), at ``frequency_hz`` [Hz] and ``temperature_c`` [°C]; the model protocol
        (:mod:`physmodel.protocol`).  [SI: m/V for an actuator, A/m for a sensor]"""
        q = self.primary_quantity
        return self.frequency_response(frequency_hz, np.atleast_1d(temperature_c), quantities=(q,))[q][0]

    def frequency_response(self, frequency_hz, temperature_c, quantities=None, out=None,
                           progress=None) -> FrequencyResponse:
        """Frequency responses at ``frequency_hz`` [Hz] and ``temperature_c`` [°C]."""
        qs = self._check_quantities(quantities or self.quantities)
        f = check_frequencies(frequency_hz)
        T = np.atleast_1d(real_array(temperature_c, "temperature_c", "°C"))
        with np.errstate(all="ignore"):       # overflow far outside the valid band: checked below
            vals = evaluate_grid(self.state(T), 2j * np.pi * f, self._kernel, qs, self.chunk_size, out, progress)
        check_finite_output(vals, f, T)
        return FrequencyResponse(
            frequency_hz=f, temperature_c=T, parameter_sets=self._names,
            values=vals, units={q: self.units[q] for q in qs},
            descriptions={q: self.descriptions[q] for q in qs},
        )
