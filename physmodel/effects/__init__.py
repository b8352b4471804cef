"""Candidate physical effects (and measurement-chain effects) composable with any physics model.

:mod:`physmodel.effects.library` holds the registry (``LIBRARY``) and ``EffectModel``;
:mod:`~physmodel.effects.physical` and :mod:`~physmodel.effects.chain` declare the effects.
"""

from .base import Effect, EffectParameter
from .library import (
                      ALIASES,
                      ALL_EFFECTS,
                      CONFUSABLE,
                      DEFAULT_QUANTITY,
                      KINDS,
                      LIBRARY,
                      OUT_OF_LIBRARY,
                      EffectActuatorModel,
                      EffectModel,
                      EffectSensorModel,
                      candidate_free_parameters,
                      candidates_for,
                      declared_confusable,
                      get_effect,
                      make_effect_model,
                      normalize_effects,
                      split_values,
)

__all__ = ["Effect", "EffectParameter", "LIBRARY", "OUT_OF_LIBRARY", "ALL_EFFECTS", "ALIASES", "KINDS",
           "DEFAULT_QUANTITY", "CONFUSABLE", "declared_confusable", "EffectModel", "EffectActuatorModel", "EffectSensorModel", "make_effect_model",
           "get_effect", "candidates_for", "normalize_effects", "split_values", "candidate_free_parameters"]
