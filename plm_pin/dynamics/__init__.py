"""Closed-chain dynamics: trajectories on the closure manifold, inverse and forward dynamics, task space."""

from .inverse_dynamics import TERMS, InverseDynamics, InverseDynamicsFailed, inverse_dynamics
from .simulation import SimulationResult, simulate
from .trajectory import (
    JointTrajectory,
    Profile,
    actuator_trajectory,
    differentiated_profile,
    sampled_profile,
    task_trajectory,
)
from .work import AdaptiveWork, adaptive_trapezoid_work, power_along, spline_work

__all__ = [
    "TERMS",
    "AdaptiveWork",
    "InverseDynamics",
    "InverseDynamicsFailed",
    "JointTrajectory",
    "Profile",
    "SimulationResult",
    "actuator_trajectory",
    "adaptive_trapezoid_work",
    "differentiated_profile",
    "inverse_dynamics",
    "power_along",
    "sampled_profile",
    "simulate",
    "spline_work",
    "task_trajectory",
]
