"""Frequency-response data from other tools: python-control FRD objects and plain arrays.

:func:`as_sweep` turns what a user has into the library's one record, :class:`FrequencySweep`:

* a ``FrequencySweep`` (returned as is), or a sequence of them (merged, distinct temperatures);
* a ``control.FrequencyResponseData`` (SISO, continuous time; ω in rad/s) with ``temperature_c``;
* a mapping ``{temperature_c: FRD or (frequency_hz, response)}``, or a sequence of FRDs with a
  sequence ``temperature_c`` of the same length;
* arrays ``(frequency_hz, response)`` with ``temperature_c`` a scalar or one value per line.

An FRD carries no units: give ``input_unit``/``output_unit`` (e.g. ``"V"``, ``"mm"``) when the
consumer checks them (calibration does: ``calibrate(frd, base, free, temperature_c=30,
input_unit="V", output_unit="mm")``).  The same arguments label a dimensionless sweep (e.g. an
estimate from bare arrays) and convert a sweep in other units of the same kind.  Lines are sorted
by frequency within each temperature.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import IPMCError
from .sweep import FrequencySweep, merge_sweeps
from .units import unit_scale

__all__ = ["as_sweep", "is_frd"]


def is_frd(obj: Any) -> bool:
    """True for a ``control.FrequencyResponseData`` (checked without importing control)."""
    return type(obj).__name__ == "FrequencyResponseData" and hasattr(obj, "omega")


def _frd_arrays(frd: Any, where: str) -> tuple[np.ndarray, np.ndarray]:
    if getattr(frd, "ninputs", 1) != 1 or getattr(frd, "noutputs", 1) != 1:
        raise IPMCError(f"{where}: the FRD must be SISO; got {frd.ninputs} inputs and {frd.noutputs} outputs")
    dt = getattr(frd, "dt", 0)
    if dt not in (0, None):
        raise IPMCError(f"{where}: the FRD must be continuous-time (dt = 0); got dt = {dt!r}")
    data = getattr(frd, "frdata", None)
    if data is None:            # python-control < 0.10.2
        data = frd.fresp
    H = np.asarray(data, dtype=complex).reshape(-1)
    w = np.asarray(frd.omega, dtype=float).reshape(-1)
    if H.size != w.size:
        raise IPMCError(f"{where}: {w.size} frequencies but {H.size} responses")
    return w / (2 * np.pi), H


def _pair(obj: Any, where: str) -> tuple[np.ndarray, np.ndarray]:
    if is_frd(obj):
        return _frd_arrays(obj, where)
    if isinstance(obj, FrequencySweep):
        if obj.temperatures().size != 1:
            raise IPMCError(f"{where}: a sweep given for one temperature holds {obj.temperatures().tolist()} °C")
        return obj.frequency_hz, obj.response
    if isinstance(obj, tuple | list) and len(obj) == 2:
        try:
            f = np.asarray(obj[0], dtype=float).reshape(-1)
            H = np.asarray(obj[1], dtype=complex).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise IPMCError(f"{where}: (frequency_hz, response) must be numeric arrays ({exc})") from None
        if f.size != H.size:
            raise IPMCError(f"{where}: {f.size} frequencies but {H.size} responses")
        return f, H
    raise IPMCError(f"{where}: expected a control.FrequencyResponseData or (frequency_hz, response); "
                    f"got {type(obj).__name__}")


def _build(T: np.ndarray, f: np.ndarray, H: np.ndarray, labels: dict, meta: dict) -> FrequencySweep:
    order = np.lexsort((f, T))            # by temperature, then frequency
    return FrequencySweep(T[order], f[order], H[order], metadata=meta, **labels)


def _relabel(sw: FrequencySweep, input_unit: str | None, output_unit: str | None) -> FrequencySweep:
    """``sw`` in the given units: a dimensionless side is labelled, another unit converted."""
    if input_unit is None and output_unit is None:
        return sw
    iu, ou = input_unit or sw.input_unit, output_unit or sw.output_unit
    for arg, u in (("input_unit", iu), ("output_unit", ou)):
        try:
            unit_scale(u)
        except IPMCError as exc:
            raise IPMCError(f"as_sweep: {arg}={u!r}: {exc}") from None
    if sw.input_unit == "1" and iu != "1":          # dimensionless: labelled, not converted
        sw = replace(sw, input_unit=iu)
    if sw.output_unit == "1" and ou != "1":
        sw = replace(sw, output_unit=ou)
    try:
        return sw.in_units(iu, ou)
    except IPMCError as exc:
        raise IPMCError(f"as_sweep: input_unit={iu!r}/output_unit={ou!r}: {exc}") from None


def as_sweep(obj: Any, temperature_c: Any = None, *, input_name: str = "input", input_unit: str | None = None,
             output_name: str = "output", output_unit: str | None = None) -> FrequencySweep:
    """A :class:`FrequencySweep` from a sweep, FRD object(s), a mapping or arrays (see the module doc).

    Parameters
    ----------
    obj : FrequencySweep, sequence of FrequencySweep, control.FrequencyResponseData, mapping, tuple
        The data.
    temperature_c : float or array_like, optional
        Temperature [°C]: a scalar for one FRD / one ``(frequency_hz, response)`` pair, a sequence
        for a sequence of FRDs, or one value per line for arrays.  Not used for sweeps or mappings.
    input_name, input_unit, output_name, output_unit : str
        Labels and units of the response (``output_unit``/``input_unit``; default ``"1"``,
        dimensionless).  For sweeps: a dimensionless side takes the unit given, another unit is
        converted to it (same kind only).

    Raises
    ------
    IPMCError
        naming the item and what was expected.
    """
    labels = dict(input_name=input_name, input_unit=input_unit or "1", output_name=output_name,
                  output_unit=output_unit or "1")
    if isinstance(obj, FrequencySweep):
        return _relabel(obj, input_unit, output_unit)
    if isinstance(obj, Sequence) and not isinstance(obj, str | bytes) and obj \
            and all(isinstance(s, FrequencySweep) for s in obj):
        return _relabel(merge_sweeps(list(obj)), input_unit, output_unit)
    meta = {"source": "physmodel.data.interop.as_sweep"}
    if isinstance(obj, Mapping):
        if not obj:
            raise IPMCError("as_sweep: the mapping {temperature_c: data} is empty")
        Ts, fs, Hs = [], [], []
        for key, val in obj.items():
            try:
                t = float(key)
            except (TypeError, ValueError):
                raise IPMCError(f"as_sweep: mapping keys must be temperatures in °C; got {key!r}") from None
            f, H = _pair(val, f"as_sweep[{key!r}]")
            Ts.append(np.full(f.size, t))
            fs.append(f)
            Hs.append(H)
        return _build(np.concatenate(Ts), np.concatenate(fs), np.concatenate(Hs), labels, meta)
    if is_frd(obj):
        if temperature_c is None or np.ndim(temperature_c) != 0:
            got = "" if temperature_c is None else f" (got temperature_c={temperature_c!r}, not a scalar)"
            raise IPMCError(f"as_sweep: an FRD carries no temperature; pass temperature_c=<°C> (a scalar) "
                            f"or a mapping {{temperature_c: frd}}{got}")
        f, H = _frd_arrays(obj, "as_sweep")
        return _build(np.full(f.size, float(temperature_c)), f, H, labels, meta)
    if isinstance(obj, Sequence) and obj and all(is_frd(x) for x in obj):
        temps = np.atleast_1d(np.asarray(temperature_c if temperature_c is not None else [], dtype=float))
        if temps.size != len(obj):
            raise IPMCError(f"as_sweep: {len(obj)} FRDs need {len(obj)} temperatures in temperature_c; "
                            f"got {temps.size}")
        return as_sweep(dict(zip(temps.tolist(), obj)), **labels)
    if isinstance(obj, tuple | list) and len(obj) == 2:
        f, H = _pair(obj, "as_sweep")
        if temperature_c is None:
            raise IPMCError("as_sweep: arrays (frequency_hz, response) need temperature_c (a scalar or one "
                            "value per line) [°C]")
        T = np.asarray(temperature_c, dtype=float)
        T = np.full(f.size, float(T)) if T.ndim == 0 else T.reshape(-1)
        if T.size != f.size:
            raise IPMCError(f"as_sweep: temperature_c has {T.size} values for {f.size} lines")
        return _build(T, f, H, labels, meta)
    raise IPMCError(f"as_sweep: cannot read frequency-response data from a {type(obj).__name__}; expected a "
                    "FrequencySweep, a control.FrequencyResponseData, a mapping {temperature_c: FRD}, or "
                    "(frequency_hz, response) arrays")
