"""Units of the data files and of the models' quantities, as multiples of SI."""

from __future__ import annotations

from ..errors import DataFormatError

#: Units the files may use, as multiples of the SI unit of their kind.
UNITS: dict[str, tuple[str, float]] = {
    "V": ("voltage", 1.0), "mV": ("voltage", 1e-3), "uV": ("voltage", 1e-6), "µV": ("voltage", 1e-6),
    "m": ("length", 1.0), "mm": ("length", 1e-3), "um": ("length", 1e-6), "µm": ("length", 1e-6),
    "A": ("current", 1.0), "mA": ("current", 1e-3), "uA": ("current", 1e-6), "µA": ("current", 1e-6),
    "nA": ("current", 1e-9),
    "Ohm": ("impedance", 1.0), "ohm": ("impedance", 1.0), "Ω": ("impedance", 1.0), "kOhm": ("impedance", 1e3),
    "N": ("force", 1.0), "mN": ("force", 1e-3),
    "1": ("dimensionless", 1.0),
}


def unit_scale(unit: str) -> float:
    """Size of ``unit`` in SI (``'mm'`` → 1e-3)."""
    if unit not in UNITS:
        raise DataFormatError(f"unknown unit {unit!r}; expected one of {sorted(UNITS)}")
    return UNITS[unit][1]


#: Display units per physical quantity of the models: (input name, unit, output name, unit, SI scale).
QUANTITY_UNITS = {
    ("actuator", "M"): ("voltage", "V", "tip_displacement", "mm"),
    ("actuator", "H"): ("voltage", "V", "tip_displacement", "mm"),
    ("actuator", "G"): ("quasi_static_displacement", "1", "tip_displacement", "1"),
    ("actuator", "Z"): ("current", "A", "voltage", "V"),
    ("actuator", "I"): ("voltage", "V", "current", "A"),
    ("sensor", "S"): ("tip_displacement", "mm", "current", "uA"),
    ("sensor", "Z"): ("current", "A", "voltage", "V"),
}
