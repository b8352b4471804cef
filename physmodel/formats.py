"""The names and versions of the library's JSON files for physics, in one place: the model file
(:mod:`physmodel.model_file`) and the bare parameter-set file
(:func:`physmodel.save_parameter_set`), and the one rule for writing them as strict JSON."""

from __future__ import annotations

import math

#: Format name and version of the model file.
MODEL_FORMAT = "ipmc-model"
MODEL_VERSION = 1

#: Format name and version of a bare parameter-set file (:func:`physmodel.save_parameter_set`).
PARAMETER_SET_FORMAT = "ipmc-parameter-set"
PARAMETER_SET_VERSION = 1


def finite_json(obj):
    """``obj`` with infinite floats as the strings "inf"/"-inf" (which ``float()`` reads back), so
    that it is strict JSON (NaN is left to fail there: a parameter is never NaN).

    Parameters
    ----------
    obj : dict, list, tuple, float or any
        The data to write.

    Returns
    -------
    object
        The same structure with infinities as strings.
    """
    if isinstance(obj, dict):
        return {str(k): finite_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite_json(v) for v in obj]
    if isinstance(obj, float) and math.isinf(obj):
        return "inf" if obj > 0 else "-inf"
    return obj


def read_json(path, what: str):
    """The JSON held in the file at ``path``; a :class:`~physmodel.errors.ParameterError` naming the
    file (``what`` says which kind) when it cannot be read as text or is not valid JSON.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file is, for messages (e.g. ``"model file"``).
    """
    import json

    from .data.files import read_text
    from .errors import DataFormatError, ParameterError

    try:
        return json.loads(read_text(path, what))
    except DataFormatError as exc:
        raise ParameterError(str(exc)) from None
    except json.JSONDecodeError as exc:
        raise ParameterError(f"{what} {str(path)!r} is not valid JSON: {exc}") from None


__all__ = ["read_json", "MODEL_FORMAT", "MODEL_VERSION", "PARAMETER_SET_FORMAT", "PARAMETER_SET_VERSION", "finite_json"]
