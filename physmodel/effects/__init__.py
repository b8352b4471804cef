"""Candidate physical effects (and measurement-chain effects) composable with any physics model.

See :mod:`physmodel.effects.library` for the effect declarations, ``LIBRARY``, ``EffectModel``.
"""

from .library import (ALL_EFFECTS, DEFAULT_QUANTITY, KINDS, LIBRARY, OUT_OF_LIBRARY, Effect, EffectActuatorModel,
                      EffectModel, EffectParameter, EffectSensorModel, candidates_for, get_effect, make_effect_model,
                      normalize_effects, split_values)

__all__ = ["Effect", "EffectParameter", "LIBRARY", "OUT_OF_LIBRARY", "ALL_EFFECTS", "KINDS", "DEFAULT_QUANTITY",
           "EffectModel", "EffectActuatorModel", "EffectSensorModel", "make_effect_model", "get_effect",
           "candidates_for", "normalize_effects", "split_values"]
