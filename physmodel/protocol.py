"""The one model interface of the library.

Every model — the physics (:class:`~physmodel.actuator.ActuatorModel`,
:class:`~physmodel.sensor.SensorModel`, the effect models of :mod:`physmodel.effects`) and the
fitted surrogates (:class:`surrogate.RationalModel`) — has

``kind``
    ``"actuator"`` (voltage in, tip displacement out), ``"sensor"`` (tip displacement in, current
    out) or ``"rational"`` (a fitted transfer function in the units of its data).
``response(frequency_hz, temperature_c) -> ndarray``
    the complex primary response, shape (n_T, n_f), at frequencies [Hz] and temperatures [°C]:
    M [m/V] for an actuator, S = I/w [A/m] for a sensor, the fitted H [output/input] for a
    rational model.

so plots, comparisons and the command line treat them alike (``isinstance(m, FrequencyModel)``).
Physics models also offer ``frequency_response(...)`` with every quantity (Z, H, G, M, I, S) and
parameter set; rational models ``at(T)`` (a python-control ``TransferFunction``) for inversion.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

#: The kinds a model can declare.
MODEL_KINDS = ("actuator", "sensor", "rational")


@runtime_checkable
class FrequencyModel(Protocol):
    """Anything with a ``kind`` and a primary frequency ``response`` (see the module doc)."""

    kind: str

    def response(self, frequency_hz, temperature_c) -> np.ndarray:
        """Complex primary response, shape (n_T, n_f). [SI of the model's quantity]"""
        ...


#: Kinds of physics model and the primary quantity each responds with.
PHYSICS_KINDS = {"actuator": "M", "sensor": "S"}


def physics_model(kind: str, params, *, kernel: str = "boundary_charge", chunk_size: int | None = None):
    """The physics model of ``kind`` ("actuator" or "sensor") for one or several parameter sets —
    the one place a kind string becomes a model.  ``kernel`` applies to sensors only."""
    from .actuator import ActuatorModel
    from .errors import IPMCError
    from .sensor import SensorModel

    kw = {} if chunk_size is None else {"chunk_size": int(chunk_size)}
    if kind == "actuator":
        return ActuatorModel(params, **kw)
    if kind == "sensor":
        return SensorModel(params, kernel=kernel, **kw)
    raise IPMCError(f"model kind {kind!r}; expected one of {sorted(PHYSICS_KINDS)}")
