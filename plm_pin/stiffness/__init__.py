"""Elastostatics of closed chains: compliant model, Cartesian stiffness, deflection, natural frequencies."""

from .cartesian import EigenStiffness, StiffnessResult, stiffness
from .deflection import Deflection, deflection
from .equilibrium import ElasticState, elastic_state
from .maps import StiffnessMap, stiffness_map
from .model import CompliantModel, compliant_model
from .vibration import MODELS, Vibration, natural_frequencies

__all__ = [
    "MODELS",
    "CompliantModel",
    "Deflection",
    "EigenStiffness",
    "ElasticState",
    "StiffnessMap",
    "StiffnessResult",
    "Vibration",
    "compliant_model",
    "deflection",
    "elastic_state",
    "natural_frequencies",
    "stiffness",
    "stiffness_map",
]
