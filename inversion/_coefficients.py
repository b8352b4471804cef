"""(num, den) of any SISO model the inversion accepts: python-control transfer functions and
state spaces, (num, den) pairs, objects with ``num``/``den`` or ``coefficients(T)``."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._errors import InversionError


def _strip(c: np.ndarray) -> np.ndarray:
    nz = np.flatnonzero(c)
    if nz.size == 0:
        return c[:0]
    return c[nz[0]:]


def model_coefficients(model: Any) -> tuple[np.ndarray, np.ndarray]:
    """Return ``(num, den)`` (descending powers of s, leading zeros stripped) of a SISO model.

    Parameters
    ----------
    model : control.TransferFunction, control.StateSpace, or (num, den)
        Continuous-time SISO model ``G(s)``.  A pair of coefficient sequences is read as
        descending powers of ``s`` [s in rad/s].

    Raises
    ------
    InversionError
        for MIMO, discrete-time, improper (``deg num > deg den``), zero or non-finite models.
    """
    num: Any
    den: Any
    if isinstance(model, tuple | list) and len(model) == 2:
        num, den = model
    else:
        try:
            import control  # local: keep import cost out of the module import
        except ImportError:  # pragma: no cover - control is a hard dependency
            control = None
        if control is not None and isinstance(model, control.StateSpace):
            if model.ninputs != 1 or model.noutputs != 1:
                raise InversionError(
                    f"model must be SISO; got a state-space model with {model.ninputs} inputs "
                    f"and {model.noutputs} outputs")
            if not model.isctime():
                raise InversionError(
                    f"model must be continuous-time; got sampling time dt={model.dt}")
            model = control.ss2tf(model)
        if hasattr(model, "num") and hasattr(model, "den"):
            if getattr(model, "ninputs", 1) != 1 or getattr(model, "noutputs", 1) != 1:
                raise InversionError(
                    f"model must be SISO; got {model.ninputs} inputs and {model.noutputs} outputs")
            dt = getattr(model, "dt", 0)
            if dt not in (0, None):
                raise InversionError(
                    f"model must be continuous-time (dt=0); got sampling time dt={dt}")
            num, den = model.num, model.den
            # python-control stores num[0][0]
            while isinstance(num, list | tuple) and len(num) == 1 and not np.isscalar(num[0]):
                num = num[0]
            while isinstance(den, list | tuple) and len(den) == 1 and not np.isscalar(den[0]):
                den = den[0]
        elif hasattr(model, "at"):
            raise InversionError(
                "model looks like a temperature-scheduled surrogate (it has .at(T)); pass "
                "model.at(temperature_c) or use inversion.invert_scheduled(model.at, ...)")
        else:
            raise InversionError(
                f"cannot read a transfer function from a {type(model).__name__}; expected a "
                "control.TransferFunction, control.StateSpace or a (num, den) pair")
    try:
        num_a = np.atleast_1d(np.asarray(num, dtype=float)).ravel()
        den_a = np.atleast_1d(np.asarray(den, dtype=float)).ravel()
    except (TypeError, ValueError) as exc:
        raise InversionError(f"model coefficients must be real numbers: {exc}") from exc
    if not (np.all(np.isfinite(num_a)) and np.all(np.isfinite(den_a))):
        raise InversionError(
            f"model coefficients must be finite; got num={num_a.tolist()}, den={den_a.tolist()}")
    num_a, den_a = _strip(num_a), _strip(den_a)
    if num_a.size == 0:
        raise InversionError("model numerator is identically zero; G = 0 has no inverse")
    if den_a.size == 0:
        raise InversionError("model denominator is identically zero")
    if num_a.size > den_a.size:
        raise InversionError(
            f"model must be proper (deg num <= deg den); got deg num = {num_a.size - 1} > "
            f"deg den = {den_a.size - 1}")
    return num_a, den_a
