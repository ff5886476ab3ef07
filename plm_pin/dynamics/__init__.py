"""Closed-chain dynamics: trajectories on the closure manifold, inverse and forward dynamics, task space."""

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
    "actuator_trajectory",
    "differentiated_profile",
    "sampled_profile",
    "task_trajectory",
]
