"""Closed-chain dynamics: trajectories on the closure manifold, inverse and forward dynamics, task space."""

from .decoupling import DecouplingReport, EntryBehaviour, decoupling_check, task_velocities
from .inverse_dynamics import TERMS, InverseDynamics, inverse_dynamics
from .simulation import SimulationResult, simulate
from .task_space import TaskSpaceDynamics, task_space_dynamics
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
    "DecouplingReport",
    "EntryBehaviour",
    "InverseDynamics",
    "JointTrajectory",
    "Profile",
    "SimulationResult",
    "TaskSpaceDynamics",
    "actuator_trajectory",
    "adaptive_trapezoid_work",
    "decoupling_check",
    "differentiated_profile",
    "inverse_dynamics",
    "power_along",
    "sampled_profile",
    "simulate",
    "spline_work",
    "task_space_dynamics",
    "task_trajectory",
    "task_velocities",
]
