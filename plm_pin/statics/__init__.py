"""Statics of closed chains: balance, redundant actuator-force allocation, reactions, force capability."""

from .allocation import OBJECTIVES
from .balance import JointLoad, Load, StaticBalance, static_balance
from .capability import Capability, InternalRange, force_capability, internal_force_range, wrench_polygon
from .forces import (
    AllocationRule,
    InternalDirection,
    StaticForces,
    actuator_limits,
    internal_directions,
    solve_balance,
    static_forces,
)
from .reactions import JointReaction, LinkForce
from .transmission import Transmission, transmission

__all__ = [
    "OBJECTIVES",
    "AllocationRule",
    "Capability",
    "InternalDirection",
    "InternalRange",
    "JointLoad",
    "JointReaction",
    "LinkForce",
    "Load",
    "StaticBalance",
    "StaticForces",
    "Transmission",
    "actuator_limits",
    "force_capability",
    "internal_directions",
    "internal_force_range",
    "solve_balance",
    "static_balance",
    "static_forces",
    "transmission",
    "wrench_polygon",
]
