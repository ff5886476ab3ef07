"""Closed-chain dynamics: trajectories on the closure manifold, inverse and forward dynamics, task space."""

from .simulation import SimulationResult, simulate
from .trajectory import (
    JointTrajectory,
    Profile,
    actuator_trajectory,
    differentiated_profile,
    sampled_profile,
    task_trajectory,
)

__all__ = [
    "JointTrajectory",
    "Profile",
    "SimulationResult",
    "actuator_trajectory",
    "differentiated_profile",
    "sampled_profile",
    "simulate",
    "task_trajectory",
]
